"""The code passes ruff: line length, pyflakes (unused imports among them) and import order.

The rules live in pyproject.toml's [tool.ruff]; this test runs `ruff check` over src, tests and
benchmarks so that the suite fails on a finding, and prints ruff's report when it does.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

try:  # the `test` extra installs ruff; find_ruff_bin locates the binary its wheel ships
    from ruff import find_ruff_bin
except ImportError:
    find_ruff_bin = None

REPO = Path(__file__).resolve().parents[1]
TREES = ("src", "tests", "benchmarks")


@pytest.mark.skipif(find_ruff_bin is None, reason="ruff not installed (pip install -e '.[test]')")
def test_ruff_check_is_clean():
    # --no-cache: no .ruff_cache written into the repository; --no-fix: report, never edit
    proc = subprocess.run([find_ruff_bin(), "check", "--no-cache", "--no-fix", "--output-format", "concise", *TREES],
                          cwd=REPO, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"ruff check {' '.join(TREES)} found problems:\n{proc.stdout}{proc.stderr}"


@pytest.mark.skipif(find_ruff_bin is None, reason="ruff not installed (pip install -e '.[test]')")
def test_ruff_reads_the_project_configuration():
    """The config above is the one ruff applies: a clean run must not mean that no rule was selected."""
    proc = subprocess.run([find_ruff_bin(), "check", "--show-settings", "src/uavcas/__init__.py"],
                          cwd=REPO, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    settings = proc.stdout
    assert "line_length = 120" in settings
    for rule in ("line-too-long (E501)", "unused-import (F401)", "unsorted-imports (I001)"):
        assert rule in settings, f"ruff does not select {rule}: is [tool.ruff] in pyproject.toml?"
