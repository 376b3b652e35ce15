"""Shared test fixtures: where the real data is, and the markers that sort the suite into tiers.

Tiers (README "Tests"): `pytest -m "not slow"` is the contributor's gate (no root, no emulation,
no estimator checks); the whole suite is what CI runs. Markers come from a test's path, not from
its author's memory: every test in a file named `*_root.py` is `root` and `slow` (it builds
network namespaces and runs in real time), scikit-learn's estimator checks are `slow`, and a
`root` mark outside a `*_root.py` file is refused at collection, so no root test can slip into
the fast tier.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

# Synthetic-dataset fixtures shared by tests/analysis and tests/ids; real campaigns shared by the
# root tests that read them (each runs once per session, and only when a selected test asks).
pytest_plugins = ["synthetic_fixtures", "helpers.root_campaigns"]

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("UAVCAS_SHARED_DATA", REPO.parent / "shared" / "data"))


def _root_reason() -> str | None:
    if os.geteuid() != 0:
        return "needs root (network namespaces); run as root to include it"
    if shutil.which("ip") is None:
        return "needs iproute2 (`ip`); run scripts/setup.sh as root"
    if not Path("/proc/self/ns/net").exists():
        return "this kernel has no network namespaces"
    return None


# test files marked slow as a whole (beyond the root files): scikit-learn's estimator checks, one
# item per (estimator, check), about a third of the suite's items
SLOW_FILES = frozenset({"ids/test_estimator_checks.py"})


def _is_root_file(path: Path) -> bool:
    return path.name.endswith("_root.py")


@pytest.hookimpl(tryfirst=True)  # before `-m` deselects: the tiers see the markers added here
def pytest_collection_modifyitems(config, items):
    root_reason = _root_reason()
    shared_missing = not SHARED_DATA.is_dir()
    misplaced = []
    for item in items:
        path = Path(str(item.fspath))
        rel = path.relative_to(REPO / "tests").as_posix() if path.is_relative_to(REPO / "tests") else path.name
        if _is_root_file(path):
            item.add_marker(pytest.mark.root)
            item.add_marker(pytest.mark.slow)
        elif "root" in item.keywords:
            misplaced.append(item.nodeid)
        if rel in SLOW_FILES:
            item.add_marker(pytest.mark.slow)
        if root_reason and "root" in item.keywords:
            item.add_marker(pytest.mark.skip(reason=root_reason))
        if shared_missing and "shared" in item.keywords:
            item.add_marker(pytest.mark.skip(reason=f"real data not found at {SHARED_DATA}"))
    if misplaced:
        raise pytest.UsageError(f"root tests outside a *_root.py file (the tiers go by file name): {misplaced[0]}"
                                f"{f' and {len(misplaced) - 1} more' if len(misplaced) > 1 else ''}")


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Root of ../shared/data; tests using it must also carry @pytest.mark.shared."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real data not found at {SHARED_DATA}")
    return SHARED_DATA
