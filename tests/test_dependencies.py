"""pyproject.toml declares exactly what the code imports (read with `ast`, nothing is imported).

- every third-party import in src/uavcas is declared (runtime, or an extra),
- every runtime dependency is imported somewhere in src/uavcas,
- an import only an extra provides (torch, h5py, dpkt) is optional where it happens: inside a
  function, a `try: ... except ImportError`, or an `if TYPE_CHECKING:` block, or in a module that
  src itself reaches only that way (or not at all: `uavcas.testing`),
- tests/ and benchmarks/ import only what the runtime list and the extras declare, and every extra
  is imported by the code it is declared for (or is a pytest plugin).
"""

from __future__ import annotations

import ast
import functools
import re
import sys
import tomllib
from dataclasses import dataclass
from importlib.metadata import entry_points, packages_distributions
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SRC = REPO / "src"
# Import names whose distribution is named otherwise, for when the distribution is not installed
# here (installed ones are found through importlib.metadata.packages_distributions()).
ALIASES = {"sklearn": "scikit-learn", "yaml": "pyyaml", "PIL": "pillow", "dateutil": "python-dateutil"}
# What each extra is for: the trees whose imports it satisfies (the `test` extra also serves
# uavcas.testing, the helpers shared by the tests and the benchmarks).
EXTRA_USERS = {"test": ("tests", "src"), "bench": ("benchmarks", "src"), "dl": ("src", "benchmarks"),
               "mat73": ("src",)}


def _norm(dist: str) -> str:
    """PEP 503 name normalisation: 'Scikit_Learn' -> 'scikit-learn'."""
    return re.sub(r"[-_.]+", "-", dist).lower()


def _req_name(req: str) -> str:
    return _norm(re.match(r"[A-Za-z0-9._-]+", req).group(0))


@dataclass(frozen=True)
class Import:
    path: Path
    line: int
    module: str  # dotted name as written (absolute), or the resolved name of a relative import
    optional: bool  # inside a function, a try/except ImportError, or an `if TYPE_CHECKING:` block


def _catches_import_error(node: ast.Try) -> bool:
    names = set()
    for h in node.handlers:
        for t in (h.type.elts if isinstance(h.type, ast.Tuple) else [h.type]) if h.type is not None else []:
            names.add(t.id if isinstance(t, ast.Name) else getattr(t, "attr", ""))
    return bool(names & {"ImportError", "ModuleNotFoundError"})


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _module_of(path: Path, root: Path) -> tuple[str, bool]:
    parts = list(path.relative_to(root).with_suffix("").parts)
    is_pkg = parts[-1] == "__init__"
    return ".".join(parts[:-1] if is_pkg else parts), is_pkg


def imports_of(path: Path, root: Path) -> list[Import]:
    """Every import in the file, relative ones resolved against its package; dynamic imports with
    a literal name (`importlib.import_module("x")`, `pytest.importorskip("x")`) count too."""
    modname, is_pkg = _module_of(path, root)
    package = modname.split(".") if is_pkg else modname.split(".")[:-1]
    out: list[Import] = []

    def visit(node: ast.AST, optional: bool) -> None:
        for child in ast.iter_child_nodes(node):
            opt = optional
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                opt = True
            if isinstance(node, ast.Try) and child in node.body and _catches_import_error(node):
                opt = True
            if isinstance(node, ast.If) and child in node.body and _is_type_checking(node):
                opt = True
            if isinstance(child, ast.Import):
                out.extend(Import(path, child.lineno, a.name, opt) for a in child.names)
            elif isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    anchor = package[: len(package) - (child.level - 1)]
                    base = ".".join([*anchor, *([base] if base else [])])
                out.append(Import(path, child.lineno, base, opt))
                # `from pkg import submodule` imports the submodule too
                out.extend(Import(path, child.lineno, f"{base}.{a.name}", opt) for a in child.names)
            elif (isinstance(child, ast.Call) and isinstance(child.func, ast.Attribute)
                  and child.func.attr in ("import_module", "importorskip") and child.args
                  and isinstance(child.args[0], ast.Constant) and isinstance(child.args[0].value, str)):
                out.append(Import(path, child.lineno, child.args[0].value, opt))
            visit(child, opt)

    visit(ast.parse(path.read_text(encoding="utf-8"), str(path)), False)
    return out


def _local_names(tree: Path) -> set[str]:
    """Top-level names a tree's own files can be imported by (test modules, tests/helpers, ...)."""
    names = {p.stem for p in tree.rglob("*.py")}
    return names | {p.name for p in tree.rglob("*") if p.is_dir()}


def _third_party(imps: list[Import], local: set[str]) -> list[Import]:
    std = set(sys.stdlib_module_names) | {"__future__"}
    return [i for i in imps if i.module and i.module.split(".")[0] not in std | local | {"uavcas"}]


@functools.cache
def _installed() -> dict[str, list[str]]:
    return packages_distributions()  # scans every installed distribution: once


@functools.cache
def _dists_of(top: str) -> frozenset[str]:
    return frozenset({_norm(d) for d in _installed().get(top, [])} | {_norm(ALIASES.get(top, top))})


@pytest.fixture(scope="module")
def declared() -> dict[str, set[str]]:
    """'runtime' and each extra -> the normalised distribution names it lists."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    out = {"runtime": {_req_name(r) for r in project["dependencies"]}}
    out.update({k: {_req_name(r) for r in v} for k, v in project.get("optional-dependencies", {}).items()})
    return out


@functools.cache
def _tree_imports(name: str) -> list[Import]:
    if name == "src":
        return [i for p in sorted((SRC / "uavcas").rglob("*.py")) for i in imports_of(p, SRC)]
    root = REPO / name
    return [i for p in sorted(root.rglob("*.py")) for i in imports_of(p, root)]


@pytest.fixture(scope="module")
def src_imports() -> list[Import]:
    return _tree_imports("src")


def _where(imps: list[Import]) -> str:
    sites = dict.fromkeys(f"{i.module.split('.')[0]} at {i.path.relative_to(REPO)}:{i.line}" for i in imps)
    return "; ".join(sites)


def test_every_third_party_import_in_src_is_declared(declared, src_imports):
    every = set().union(*declared.values())
    missing = [i for i in _third_party(src_imports, set()) if not _dists_of(i.module.split(".")[0]) & every]
    assert not missing, f"imported but declared nowhere in pyproject.toml: {_where(missing)}"


def test_every_runtime_dependency_is_imported_in_src(declared, src_imports):
    """By the package proper: what only uavcas.testing imports belongs to the test extra."""
    proper = [i for i in src_imports if not _module_of(i.path, SRC)[0].startswith("uavcas.testing")]
    used = set().union(*(_dists_of(i.module.split(".")[0]) for i in _third_party(proper, set())))
    unused = sorted(declared["runtime"] - used)
    assert not unused, f"declared runtime dependencies nothing in src/uavcas imports: {unused}"


def _eager_modules(src_imports: list[Import]) -> set[str]:
    """The uavcas modules loaded without a deferred import: those reachable through module-level,
    unguarded imports from the modules nothing imports statically (entry points, `python -m`
    targets, the attack families the registry imports by name); `uavcas.testing` is opt-in."""
    modules = {_module_of(p, SRC)[0] for p in (SRC / "uavcas").rglob("*.py")}
    edges: dict[str, set[str]] = {m: set() for m in modules}
    imported: set[str] = set()
    for i in src_imports:
        parts = i.module.split(".")
        targets = {".".join(parts[:k]) for k in range(1, len(parts) + 1)} & modules  # parents load first
        src_mod = _module_of(i.path, SRC)[0]
        imported |= targets - {src_mod}
        if not i.optional:
            edges[src_mod] |= targets
    todo = [m for m in modules if m not in imported and not m.startswith("uavcas.testing")]
    eager = set(todo)
    while todo:
        for nxt in edges[todo.pop()] - eager:
            eager.add(nxt)
            todo.append(nxt)
    return eager


def test_imports_only_an_extra_provides_are_optional(declared, src_imports):
    eager = _eager_modules(src_imports)
    bad = [i for i in _third_party(src_imports, set())
           if not _dists_of(i.module.split(".")[0]) & declared["runtime"]
           and not i.optional and _module_of(i.path, SRC)[0] in eager]
    assert not bad, ("an import no runtime dependency provides, made at module level in a module the "
                     f"package loads unconditionally (defer it into the function, or guard it): {_where(bad)}")


@pytest.mark.parametrize("tree", ["tests", "benchmarks"])
def test_tests_and_benchmarks_import_only_declared_packages(declared, tree):
    allowed = declared["runtime"].union(*(declared[e] for e, users in EXTRA_USERS.items()
                                          if tree in users and e in declared))
    imps = _third_party(_tree_imports(tree), _local_names(REPO / tree))
    missing = [i for i in imps if not _dists_of(i.module.split(".")[0]) & allowed]
    assert not missing, f"{tree}/ imports what pyproject.toml does not declare for it: {_where(missing)}"


def test_every_extra_is_used_by_the_code_it_serves(declared):
    assert set(declared) - {"runtime"} == set(EXTRA_USERS), "an extra without a line in EXTRA_USERS (or a stale one)"
    plugins = {_norm(ep.dist.name) for ep in entry_points(group="pytest11") if ep.dist is not None}
    for extra, users in EXTRA_USERS.items():
        used = set().union(*(_dists_of(i.module.split(".")[0]) for t in users
                             for i in _third_party(_tree_imports(t), set() if t == "src" else _local_names(REPO / t))))
        unused = sorted(declared[extra] - used - (plugins if extra == "test" else set()))
        assert not unused, f"extra {extra!r} lists what {', '.join(users)} never import: {unused}"


def test_the_checker_sees_guarded_relative_and_dynamic_imports(tmp_path):
    """The import reader itself: a wrong reader would make the checks above pass vacuously."""
    pkg = tmp_path / "uavcas" / "sub"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "m.py").write_text(
        "from typing import TYPE_CHECKING\nimport numpy\nfrom . import sibling\nfrom ..other import x\n"
        "try:\n    import h5py\nexcept ImportError:\n    h5py = None\n"
        "if TYPE_CHECKING:\n    import torch\n"
        "def f():\n    import dpkt\n    importlib.import_module('lightgbm')\n")
    got = {(i.module, i.optional) for i in imports_of(pkg / "m.py", tmp_path)}
    assert {("numpy", False), ("uavcas.sub.sibling", False), ("uavcas.other", False), ("h5py", True),
            ("torch", True), ("dpkt", True), ("lightgbm", True)} <= got
    assert _dists_of("sklearn") == {"scikit-learn"} or "scikit-learn" in _dists_of("sklearn")
