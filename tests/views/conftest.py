"""View tests reuse the synthetic run directory of tests/labels."""

from __future__ import annotations

import pytest

from helpers.synth_run import build_run


@pytest.fixture(scope="session")
def synth_run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("run") / "run-synth")
