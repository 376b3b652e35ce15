"""A session fixture's files built once per test session, also when pytest-xdist splits the
session over workers (`scripts/test.sh` runs the tests without root that way).

Each xdist worker is its own process with its own session, so a plain session fixture runs once
per worker: on 2 cores the synthetic dataset (~10 s) was built twice. Under xdist the workers'
base temporary directories share a parent, and the first worker to take the lock there builds;
the others wait for it and reuse the files (the pattern pytest-xdist documents for session
fixtures). Without xdist it is the plain session fixture.
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Callable
from pathlib import Path

import pytest


def built_once(tmp_path_factory: pytest.TempPathFactory, name: str, build: Callable[[Path], None]) -> Path:
    """The directory `name`, filled by `build(directory)` once for the whole session."""
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # shared by every worker of this session
    out = base / f"once-{name}"
    with open(base / f"once-{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the builder is done
        if not (out / "DONE").is_file():
            out.mkdir(exist_ok=True)
            build(out)
            (out / "DONE").touch()
    return out
