"""A temporary copy of the `uavcas` package with one module dropped in: what the registry tests
(path-loss models, feature standards, detectors) use to show that a new entry is one new module."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import uavcas


def package_with(root: Path, module: str, source: str) -> dict[str, str]:
    """Copy the installed package under `root`, write `source` as `module` (a path inside the
    package, e.g. "flows/standards/tiny.py") and return an environment that imports the copy."""
    shutil.copytree(Path(uavcas.__file__).parent, root / "uavcas", ignore=shutil.ignore_patterns("__pycache__"))
    (root / "uavcas" / module).write_text(textwrap.dedent(source))
    return {**os.environ, "PYTHONPATH": str(root), "COLUMNS": "250"}


def check_ok(code: str, root: Path, env: dict[str, str]) -> None:
    """Run `code` (given `root` as argv[1]) in the copy; it must print exactly "ok"."""
    r = subprocess.run([sys.executable, "-c", code, str(root)], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]


def package_copy(tmp: Path, modules: dict[str, str]) -> Path:
    """Copy the installed package to TMP/pkg/uavcas with `modules` (a path inside the package ->
    its source) written in; returns TMP/pkg, the PYTHONPATH entry of `run_on`."""
    dst = tmp / "pkg"
    shutil.copytree(Path(uavcas.__file__).parent, dst / "uavcas", ignore=shutil.ignore_patterns("__pycache__"))
    for module, source in modules.items():
        (dst / "uavcas" / module).write_text(source)
    return dst


def run_on(pkg: Path, *args: str, timeout_s: float = 600, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """`python ARGS` in a fresh interpreter that imports the copy at `pkg`."""
    # PYTHONPATH puts the copy before the editable install of the work tree
    env = {**os.environ, "PYTHONPATH": str(pkg), "COLUMNS": "200", "NO_COLOR": "1", "TERM": "dumb"}
    return subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True, timeout=timeout_s, cwd=cwd)
