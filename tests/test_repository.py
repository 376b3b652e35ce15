"""The repository's housekeeping: tests import their helpers as a package (no sys.path edits),
benchmarks import no test file, and no build artefact (a wheel) is tracked."""

from __future__ import annotations

import ast
import re
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
_LIST_EDITS = {"insert", "append", "extend", "remove", "pop", "clear", "__setitem__", "__delitem__"}


def _is_sys_path(node: ast.AST) -> bool:
    return (isinstance(node, ast.Attribute) and node.attr == "path" and isinstance(node.value, ast.Name)
            and node.value.id == "sys")


def sys_path_edits(source: str) -> list[int]:
    """Lines that change the import path: sys.path.insert/append/..., an assignment to sys.path
    or to an item of it, `site.addsitedir`, pytest's `monkeypatch.syspath_prepend`."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            f = node.func
            if (f.attr in _LIST_EDITS and _is_sys_path(f.value)) or f.attr in ("addsitedir", "syspath_prepend"):
                lines.append(node.lineno)
        targets = []
        if isinstance(node, (ast.Assign, ast.Delete)):
            targets = node.targets
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            targets = [node.target]
        for t in targets:
            if _is_sys_path(t) or (isinstance(t, ast.Subscript) and _is_sys_path(t.value)):
                lines.append(node.lineno)
    return sorted(lines)


def test_the_checker_finds_every_kind_of_sys_path_edit():
    src = ("import sys, site\nsys.path.insert(0, 'x')\nsys.path.append('x')\nsys.path = ['x']\n"
           "sys.path[:0] = ['x']\nsys.path += ['x']\nsite.addsitedir('x')\n"
           "def t(monkeypatch):\n    monkeypatch.syspath_prepend('x')\nprint(sys.path)\n")
    assert sys_path_edits(src) == [2, 3, 4, 5, 6, 7, 9]


def test_no_test_file_edits_sys_path():
    edits = {str(p.relative_to(REPO)): lines for p in sorted((REPO / "tests").rglob("*.py"))
             if (lines := sys_path_edits(p.read_text(encoding="utf-8")))}
    assert not edits, f"import helpers from tests/helpers (`from helpers.x import ...`) instead: {edits}"


def test_no_test_module_imports_another():
    """Shared test code lives in tests/helpers, not in a test module another one imports."""
    bad = []
    for p in sorted((REPO / "tests").rglob("*.py")):
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            bad += [f"{p.relative_to(REPO)}:{node.lineno} {n}" for n in names
                    if n.split(".")[-1].startswith("test_") or n.split(".")[0].startswith("test_")]
    assert not bad, bad


def test_benchmarks_import_no_test_file():
    """What a benchmark shares with the tests lives in uavcas.testing (or the benchmark itself)."""
    test_modules = {p.stem for p in (REPO / "tests").rglob("*.py")} | {"helpers", "tests"}
    bad = []
    for p in sorted((REPO / "benchmarks").glob("*.py")):
        src = p.read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(src)):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else [])
            bad += [f"{p.name}:{node.lineno} {n}" for n in names if n.split(".")[0] in test_modules]
        bad += [f"{p.name}:{line} edits sys.path" for line in sys_path_edits(src)]
    assert not bad, bad


def test_no_wheel_is_tracked():
    if shutil.which("git") is None or not (REPO / ".git").exists():
        pytest.skip("not a git checkout")
    tracked = subprocess.run(["git", "ls-files", "*.whl"], cwd=REPO, capture_output=True, text=True, check=True)
    assert tracked.stdout.split() == []
    ignored = subprocess.run(["git", "check-ignore", "-q", "--no-index", "some-1.0-py3-none-any.whl"], cwd=REPO)
    assert ignored.returncode == 0, ".gitignore must ignore *.whl"


def test_benchmarks_run_sh_runs_every_script_or_says_why_not_and_the_readme_agrees():
    bench = REPO / "benchmarks"
    scripts = {p.name for p in bench.glob("*.py")}
    run_sh = (bench / "run.sh").read_text(encoding="utf-8")
    ran = set(re.findall(r"^\s*run \$PY benchmarks/(\w+\.py)\b", run_sh, flags=re.M))
    said = {name for line in run_sh.splitlines() if line.lstrip().startswith("#")
            for name in re.findall(r"\b(\w+\.py)\b", line)}
    assert ran <= scripts, f"run.sh runs scripts that do not exist: {sorted(ran - scripts)}"
    assert not scripts - ran - said, f"run.sh neither runs nor explains: {sorted(scripts - ran - said)}"
    readme = (bench / "README.md").read_text(encoding="utf-8")
    intro = readme.split("\n|", 1)[0]  # the paragraph before the table: what run.sh leaves out
    table = {m for m in re.findall(r"^\| `(\w+\.py)", readme, flags=re.M)}
    assert table == scripts, f"benchmarks/README.md's table vs the scripts: {sorted(table ^ scripts)}"
    skipped = scripts - ran
    assert all(name in intro for name in skipped), f"README must say run.sh skips {sorted(skipped)}"
    assert "run.sh" in intro


def test_ci_runs_exactly_the_readmes_test_command():
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    setup = readme.split("## Two commands", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.+?)\n```", setup)
    assert len(commands) == 2 and all(c.startswith("bash scripts/setup.sh && ") for c in commands), commands
    ci = [ln for ln in (REPO / ".ci" / "run").read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    assert ci[-1] == commands[1], "the last line of .ci/run must be the README's test command, verbatim"
