"""Command-line errors are one line on stderr with a non-zero exit: never a traceback, never markup."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

UAVCAS = str(Path(sys.executable).parent / "uavcas")
CONFIG = "benign-5-2-image-logdist-adaptive-random-30-95"


def _as_unprivileged(argv: list[str]) -> list[str]:
    """As root, drop to nobody (root may write anywhere); otherwise we already are a user."""
    if os.geteuid() != 0:
        return argv
    if shutil.which("setpriv") is None:
        pytest.skip("needs setpriv (util-linux) to drop root for this check")
    drop = ["setpriv", "--reuid", "65534", "--regid", "65534", "--clear-groups"]
    if subprocess.run([*drop, "head", "-c", "1", UAVCAS], capture_output=True).returncode != 0:
        pytest.skip(f"user nobody cannot read {UAVCAS} (a checkout inside a folder only root may enter, "
                    "e.g. one made by mktemp -d)")
    return [*drop, *argv]


@pytest.mark.slow  # 6 s on 2 cores
def test_plan_into_an_unwritable_folder_is_one_line_exit_2():
    base = Path(tempfile.mkdtemp(prefix="uavcas-test-"))  # pytest's tmp_path is root-only (0700)
    try:
        base.chmod(0o755)
        ro = base / "ro"
        ro.mkdir(mode=0o555)
        r = subprocess.run(_as_unprivileged([UAVCAS, "plan", CONFIG, "--windows", "2", "--out",
                                             str(ro / "plan.json")]), capture_output=True, text=True, timeout=60)
        assert r.returncode == 2, r.stderr
        assert r.stderr == f"error: cannot write into {ro}: Permission denied\n"
        assert list(ro.iterdir()) == []
    finally:
        shutil.rmtree(base)


def test_prefix_error_keeps_its_regex():
    r = subprocess.run([UAVCAS, "doctor", "--no-measure", "--prefix", "BAD"], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2
    assert r.stderr == "error: --prefix: bad prefix 'BAD': want [a-z][a-z0-9]{1,11}\n"
