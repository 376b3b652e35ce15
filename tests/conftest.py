"""Shared test fixtures: where the real data is, and markers that skip with a reason."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

# Synthetic-dataset fixtures shared by tests/analysis and tests/ids.
pytest_plugins = ["synthetic_fixtures"]

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


def pytest_collection_modifyitems(config, items):
    root_reason = _root_reason()
    shared_missing = not SHARED_DATA.is_dir()
    for item in items:
        if root_reason and "root" in item.keywords:
            item.add_marker(pytest.mark.skip(reason=root_reason))
        if shared_missing and "shared" in item.keywords:
            item.add_marker(pytest.mark.skip(reason=f"real data not found at {SHARED_DATA}"))


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Root of ../shared/data; tests using it must also carry @pytest.mark.shared."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real data not found at {SHARED_DATA}")
    return SHARED_DATA
