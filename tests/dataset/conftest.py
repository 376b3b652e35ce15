"""Dataset tests reuse the synthetic run directory of tests/labels."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "labels"))
from synth_run import build_run  # noqa: E402


@pytest.fixture(scope="session")
def synth_run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("run") / "run-synth")
