"""No import cycle in src/uavcas, read with `ast` (nothing is imported). Two graphs:

1. The dependency graph: every import statement is an edge, wherever it stands: at module level,
   inside a function, or under `if TYPE_CHECKING:` (a type-only edge is still a dependency, and
   a function-level import is a cycle Python merely postpones). An edge goes to the module the
   statement names: `import a.b` and `from a.b import x` to `a.b`; `from a import b` to `a.b`
   when `b` is a submodule, else to `a`; relative imports resolve against the importer's package
   (a package's `__init__` is its own); `importlib.import_module("a.b")` with a constant name is
   an import, and a package that imports its submodules with `pkgutil.iter_modules(__path__)`
   (the registries) imports every one of them.
2. What Python runs on import: only the imports executed when a module is imported (not in
   functions, not under TYPE_CHECKING), and, for each, the packages on the way (importing `a.b.c`
   runs `a/__init__` and `a/b/__init__` first, unless the importer is inside them). A cycle here
   is an ImportError (or a half-initialised module) depending on which module is imported first.

Layering (issue 40): the offline stages (`OFFLINE`: everything that reads a run or a dataset
without the kernel) import neither the kernel package `uavcas.emulation` nor the report package
`uavcas.report`, by any import statement (module level, function level or TYPE_CHECKING): the pure
network model they share with the emulator is `uavcas.network`, and the one matplotlib setup is
`uavcas.figure`. Those two are leaves (`LEAVES`), and the network model is pure (no subprocess, no
kernel interface). Every top-level package is on one side, so a new package is classified in one
line (`OFFLINE` or `KERNEL_SIDE`).

And no import hides in a function (issue 26) but a deferred optional heavy dependency: `torch`
(the `dl` extra) and dask's `distributed`, or a project module that imports one of them at module
level (`uavcas.ids.nets`), each with a comment on its line or the line above saying why. The one
other: `uavcas.__getattr__` (PEP 562) gives `uavcas.load_dataset` without pandas loading with
every `import uavcas` (the CLI's root, each emulated app's process).
"""

from __future__ import annotations

import ast
import functools
import io
import tokenize
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
ROOT = "uavcas"


@dataclass(frozen=True)
class Edge:
    src: str
    dst: str
    where: str  # "path:line", for the message


def _module_name(path: Path, src: Path) -> str:
    parts = list(path.relative_to(src).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@functools.cache
def _modules(src: Path = SRC, root: str = ROOT) -> dict[str, Path]:
    return {_module_name(p, src): p for p in sorted((src / root).rglob("*.py"))}


def _ancestors(name: str) -> list[str]:
    """The packages Python imports before `name`, outermost first."""
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def _resolve(importer: str, is_package: bool, module: str | None, level: int) -> str:
    if level == 0:
        return module or ""
    package = importer if is_package else importer.rpartition(".")[0]
    parts = package.split(".")
    base = ".".join(parts[: len(parts) - (level - 1)])
    return f"{base}.{module}" if module else base


def _targets(importer: str, mods: dict[str, Path], node: ast.AST) -> Iterator[str]:
    """The modules one statement or call imports by name (before ancestors are added)."""
    is_package = mods[importer].name == "__init__.py"
    if isinstance(node, ast.Import):
        yield from (a.name for a in node.names)
    elif isinstance(node, ast.ImportFrom):
        base = _resolve(importer, is_package, node.module, node.level)
        for a in node.names:
            yield f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base
    elif isinstance(node, ast.Call):
        f = node.func
        name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""
        if name == "import_module" and node.args and isinstance(node.args[0], ast.Constant):
            yield str(node.args[0].value)
        elif (name == "iter_modules" and is_package and node.args
              and isinstance(node.args[0], ast.Name) and node.args[0].id == "__path__"):
            yield from (m for m in mods if m.rpartition(".")[0] == importer)


def _run_on_import(node: ast.AST) -> Iterator[ast.AST]:
    """The nodes Python executes when the module is imported: not function bodies, not the body
    of an `if TYPE_CHECKING:` (its `else:` runs)."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        yield child
        if isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test):
            for x in child.orelse:
                yield x
                yield from _run_on_import(x)
            continue
        yield from _run_on_import(child)


def edges(src: Path = SRC, root: str = ROOT, on_import: bool = False) -> list[Edge]:
    """Every import statement's edge (`on_import`: only the imports Python runs when the module
    is imported, plus the packages on the way to each, whose `__init__` runs first)."""
    mods = _modules(src, root)
    out: list[Edge] = []
    for importer, path in mods.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        running = set(_ancestors(importer)) | {importer}
        for node in (_run_on_import(tree) if on_import else ast.walk(tree)):
            for target in _targets(importer, mods, node):
                for dst in (_ancestors(target) + [target] if on_import else [target]):
                    if dst in mods and dst not in running:
                        out.append(Edge(importer, dst, f"{path.relative_to(src)}:{node.lineno}"))
    return out


def _components(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        found.append(sorted(comp))
    return found


def _shortest_cycle(graph: dict[str, set[str]], members: list[str]) -> list[str]:
    """A shortest cycle through the component's first module, as a list of modules."""
    inside = set(members)
    start = members[0]
    prev: dict[str, str] = {}
    frontier = [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph[v] & inside):
                if w == start:
                    path = [v]
                    while path[-1] != start:
                        path.append(prev[path[-1]])
                    return [*reversed(path), start]
                if w not in prev:
                    prev[w] = v
                    nxt.append(w)
        frontier = nxt
    raise AssertionError("a component without a cycle")


def cycles(src: Path = SRC, root: str = ROOT, on_import: bool = False) -> list[str]:
    """One message per cycle-carrying component: its modules and a shortest cycle, edge by edge."""
    all_edges = edges(src, root, on_import)
    graph: dict[str, set[str]] = {m: set() for m in _modules(src, root)}
    where: dict[tuple[str, str], str] = {}
    for e in all_edges:
        if e.src != e.dst:
            graph[e.src].add(e.dst)
            where.setdefault((e.src, e.dst), e.where)
    msgs = []
    for comp in _components(graph):
        cyc = _shortest_cycle(graph, comp)
        steps = "\n".join(f"    {a} -> {b}  ({where[a, b]})" for a, b in zip(cyc, cyc[1:]))
        msgs.append(f"{len(comp)} modules in a cycle: {', '.join(comp)}\n  e.g.\n{steps}")
    return msgs


DEFERRED_OK = ("torch", "dask", "distributed")  # optional and heavy: loaded only where used
LAZY_ATTRIBUTES = {"uavcas": "uavcas.dataset.load"}  # package -> the module its __getattr__ may import


def _comment_lines(text: str) -> set[int]:
    return {t.start[0] for t in tokenize.generate_tokens(io.StringIO(text).readline) if t.type == tokenize.COMMENT}


def _loads_deferred_ok(module: str, mods: dict[str, Path]) -> bool:
    """A project module that imports torch/dask/distributed when it is imported."""
    tree = ast.parse(mods[module].read_text(encoding="utf-8"))
    return any(t.split(".")[0] in DEFERRED_OK for node in _run_on_import(tree) for t in _targets(module, mods, node))


def function_imports(src: Path = SRC, root: str = ROOT) -> list[str]:
    """One line per import inside a function that is not a commented, deferred optional dependency."""
    mods = _modules(src, root)
    bad = []
    for module, path in mods.items():
        text = path.read_text(encoding="utf-8")
        tree = ast.parse(text, filename=str(path))
        comments = _comment_lines(text)
        seen: set[int] = set()
        for fn in ast.walk(tree):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(fn):
                if not isinstance(node, (ast.Import, ast.ImportFrom)) or id(node) in seen:
                    continue
                seen.add(id(node))
                targets = list(_targets(module, mods, node))
                ok = all(t.split(".")[0] in DEFERRED_OK or (t in mods and _loads_deferred_ok(t, mods))
                         or (fn.name == "__getattr__" and LAZY_ATTRIBUTES.get(module) == t) for t in targets)
                where = f"{path.relative_to(src)}:{node.lineno}: {ast.unparse(node)}"
                if not ok:
                    bad.append(f"{where}  (not a deferred optional dependency: import it at module level)")
                elif not comments & {node.lineno, node.lineno - 1}:
                    bad.append(f"{where}  (deferred without a comment saying why)")
    return bad


def test_the_function_import_check_tells_deferred_from_hidden(tmp_path):
    src = _tree(tmp_path, {
        "pkg/__init__.py": "def __getattr__(name):\n    from pkg.low import x  # lazy attribute\n",
        "pkg/low.py": "import os\n",
        "pkg/net.py": "try:\n    import torch\nexcept ImportError:\n    raise\n",
        "pkg/ok.py": "def f():\n    # the dl extra\n    import torch\n"
                     "    from pkg.net import N  # torch at module level\n"
                     "def g():\n    from distributed import Client  # heavy\n",
        "pkg/hidden.py": "def f():\n    import json  # why not\n    from . import low  # a cycle, postponed\n",
        "pkg/bare.py": "class C:\n    def m(self):\n        import torch\n",
    })
    _modules.cache_clear()
    try:
        assert function_imports(src, "pkg") == [
            "pkg/__init__.py:2: from pkg.low import x  (not a deferred optional dependency: import it at module level)",
            "pkg/bare.py:3: import torch  (deferred without a comment saying why)",
            "pkg/hidden.py:2: import json  (not a deferred optional dependency: import it at module level)",
            "pkg/hidden.py:3: from . import low  (not a deferred optional dependency: import it at module level)",
        ]
        LAZY_ATTRIBUTES["pkg"] = "pkg.low"
        assert not any(b.startswith("pkg/__init__") for b in function_imports(src, "pkg"))
    finally:
        LAZY_ATTRIBUTES.pop("pkg", None)
        _modules.cache_clear()


def test_imports_in_functions_are_only_deferred_optional_dependencies():
    found = function_imports()
    assert not found, f"{len(found)} imports inside functions in src/uavcas:\n" + "\n".join(found)


def _tree(tmp: Path, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        (tmp / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp / rel).write_text(text, encoding="utf-8")
    return tmp


def test_the_reader_sees_every_kind_of_import(tmp_path):
    src = _tree(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/low.py": "import os\n",
        "pkg/top.py": "from pkg.low import x\n",  # module level
        "pkg/typed.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .low import x\n",
        "pkg/late.py": "def f():\n    import pkg.sub.leaf\n",  # function level, through a package
        "pkg/sub/__init__.py": "from . import leaf\n",  # a package's own relative import
        "pkg/sub/leaf.py": "from .. import low\n",  # `from package import submodule`
        "pkg/reg/__init__.py": "import importlib, pkgutil\nfor m in pkgutil.iter_modules(__path__):\n"
                               "    importlib.import_module(m.name)\n",
        "pkg/reg/one.py": "",
        "pkg/dyn.py": "import importlib\nimportlib.import_module('pkg.top')\n",
    })
    e = {(x.src, x.dst) for x in edges(src, "pkg")}
    assert e == {
        ("pkg.top", "pkg.low"), ("pkg.typed", "pkg.low"), ("pkg.late", "pkg.sub.leaf"), ("pkg.sub", "pkg.sub.leaf"),
        ("pkg.sub.leaf", "pkg.low"),
        ("pkg.reg", "pkg.reg.one"), ("pkg.dyn", "pkg.top"),
    }
    assert cycles(src, "pkg") == []


def test_a_cycle_is_found_and_shown(tmp_path):
    src = _tree(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/a.py": "from pkg import b\n",
        "pkg/b.py": "def f():\n    from pkg.c import g\n",
        "pkg/c.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import pkg.a\n",
        "pkg/d.py": "import pkg.a\n",  # outside the cycle
    })
    (msg,) = cycles(src, "pkg")
    assert msg.startswith("3 modules in a cycle: pkg.a, pkg.b, pkg.c\n")
    assert "pkg.a -> pkg.b  (pkg/a.py:1)" in msg and "pkg.c -> pkg.a  (pkg/c.py:3)" in msg


def test_what_runs_on_import_includes_the_packages_on_the_way(tmp_path):
    src = _tree(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/a/__init__.py": "from pkg.a.top import f\n",  # a package that loads its top module
        "pkg/a/low.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import pkg.a.top\n",
        "pkg/a/top.py": "import pkg.b.low2\ndef f():\n    import pkg.a.low\n",
        "pkg/b/__init__.py": "",
        "pkg/b/low2.py": "import os\n",
    })
    e = {(x.src, x.dst) for x in edges(src, "pkg", on_import=True)}
    assert e == {("pkg.a", "pkg.a.top"), ("pkg.a.top", "pkg.b"), ("pkg.a.top", "pkg.b.low2")}
    assert cycles(src, "pkg", on_import=True) == []
    assert cycles(src, "pkg")  # the dependency graph has pkg.a.low -> pkg.a.top -> pkg.a.low
    (src / "pkg/b/low2.py").write_text("from pkg.a.low import x\n")  # runs pkg/a/__init__ first
    (msg,) = cycles(src, "pkg", on_import=True)
    assert "pkg.b.low2 -> pkg.a  (pkg/b/low2.py:1)" in msg


def test_no_import_cycle():
    found = cycles()
    assert not found, "import cycles in src/uavcas:\n" + "\n".join(found)


def test_no_cycle_in_what_runs_on_import():
    found = cycles(on_import=True)
    assert not found, "cycles among the imports src/uavcas runs on import (package __init__s included):\n" \
        + "\n".join(found)



# layering (issue 40) -------------------------------------------------------------------------------------------
KERNEL = "emulation"  # the kernel package: namespaces, tc/nft, processes; only the kernel side imports it
REPORT = "report"  # the dataset report page; nothing offline builds on it
OFFLINE = (  # read runs, plans and datasets without the kernel ("__init__": the root package's own)
    "__init__", "analysis", "atomic", "calibration", "channel", "dataset", "events", "extract", "fidelity", "figure",
    "flows", "ids", "labels", "mavlink_capture", "mobility", "network", "report", "rundir", "scenario",
    "scenario_model", "schema", "seeding", "stats", "topology", "twin", "versions", "views", "vocabulary",
)  # fmt: skip
KERNEL_SIDE = (  # may import the kernel package: they run, drive or check emulations
    "__main__", "attacks", "campaign", "cli", "diagnostics", "emulation", "testing",
    "traffic",  # the benign traffic apps (issue 40 moves them out of emulation/apps)
)  # fmt: skip
LEAVES = {"network": (), "figure": ("atomic",)}  # package -> the only other uavcas packages it may import
PURE = {"network": ("subprocess", "ctypes", "socket", "select", "fcntl", "signal", "pyroute2")}  # no kernel access


def _top(module: str) -> str:
    """The top-level package (or module) of uavcas a module belongs to."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def layering(src: Path = SRC, root: str = ROOT, offline: tuple[str, ...] = OFFLINE,
             kernel_side: tuple[str, ...] = KERNEL_SIDE, leaves: dict[str, tuple[str, ...]] = LEAVES,
             pure: dict[str, tuple[str, ...]] = PURE) -> list[str]:
    """One line per import that breaks the layering, with its file:line (every import statement)."""
    bad = []
    for e in edges(src, root):
        a, b = _top(e.src), _top(e.dst)
        if a == b:
            continue
        if a in offline and b == KERNEL:
            bad.append(f"{e.where}: {e.src} imports {e.dst} (an offline stage imports the kernel package)")
        if a in offline and b == REPORT:
            bad.append(f"{e.where}: {e.src} imports {e.dst} (an offline stage imports the report package)")
        if a in leaves and b not in leaves[a]:
            allowed = f"only {', '.join(leaves[a])}" if leaves[a] else "nothing"
            bad.append(f"{e.where}: {e.src} imports {e.dst} (a leaf: {a} imports {allowed} of uavcas)")
    mods = _modules(src, root)
    for module, path in mods.items():
        if _top(module) not in pure:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            for t in (_targets(module, mods, node) if isinstance(node, (ast.Import, ast.ImportFrom)) else ()):
                if t.split(".")[0] in pure[_top(module)]:
                    bad.append(f"{path.relative_to(src)}:{node.lineno}: {module} imports {t} (the network model is "
                               "pure: no processes, no kernel interface)")
    for top in sorted({_top(m) for m in mods} - set(offline) - set(kernel_side)):
        bad.append(f"{root}.{top}: in neither OFFLINE nor KERNEL_SIDE (tests/test_import_graph.py): classify it")
    return sorted(set(bad))


def test_the_layering_check_names_each_offending_import(tmp_path):
    src = _tree(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/emulation/__init__.py": "",
        "pkg/emulation/kernel.py": "import subprocess\nfrom pkg.network import names\n",
        "pkg/network/__init__.py": "",
        "pkg/network/names.py": "import os\n",
        "pkg/network/bad.py": "import subprocess\nfrom pkg.atomic import w\n",
        "pkg/atomic.py": "",
        "pkg/figure.py": "from pkg.atomic import w\n",
        "pkg/report/__init__.py": "from pkg.figure import plt\n",
        "pkg/report/page.py": "from pkg.flows import x\n",
        "pkg/flows/__init__.py": "x = 1\n",
        "pkg/flows/ok.py": "from pkg.network.names import n\nfrom pkg.figure import plt\n",
        "pkg/flows/late.py": "def f():\n    from pkg.emulation import kernel\n",
        "pkg/flows/typed.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import pkg.report.page\n",
        "pkg/cli.py": "import pkg.emulation.kernel\nimport pkg.report\n",
        "pkg/newpkg/__init__.py": "",
    })
    found = layering(src, "pkg", offline=("__init__", "atomic", "figure", "flows", "network", "report"),
                     kernel_side=("cli", "emulation"), leaves={"network": (), "figure": ("atomic",)},
                     pure={"network": ("subprocess",)})
    assert found == [
        "pkg.newpkg: in neither OFFLINE nor KERNEL_SIDE (tests/test_import_graph.py): classify it",
        "pkg/flows/late.py:2: pkg.flows.late imports pkg.emulation.kernel (an offline stage imports the kernel "
        "package)",
        "pkg/flows/typed.py:3: pkg.flows.typed imports pkg.report.page (an offline stage imports the report package)",
        "pkg/network/bad.py:1: pkg.network.bad imports subprocess (the network model is pure: no processes, no "
        "kernel interface)",
        "pkg/network/bad.py:2: pkg.network.bad imports pkg.atomic (a leaf: network imports nothing of uavcas)",
    ]


def test_offline_stages_import_neither_the_kernel_package_nor_the_report():
    found = layering()
    assert not found, f"{len(found)} imports break the layering of src/uavcas:\n" + "\n".join(found)
