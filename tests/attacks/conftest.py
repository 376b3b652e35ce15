"""Family tests reuse the synthetic run directory of tests/labels (scapy pcaps + a typed attack log)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "labels"))
from synth_run import T0, build_run  # noqa: E402


@pytest.fixture(scope="session")
def synth_run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("run") / "run-synth")


@pytest.fixture(scope="session")
def truth_ctx(synth_run_dir):
    """A TruthContext of the synthetic run, and its attack log."""
    from uavcas.flows import FlowConfig, extract_flows
    from uavcas.labels import TruthContext, read_attack_log
    from uavcas.rundir import RunDir

    rd = RunDir(synth_run_dir)
    ex = extract_flows(rd.pcaps(), FlowConfig(view="5tuple"))
    log = read_attack_log(rd.attacks_jsonl, rd.read_plan(), T0)
    return TruthContext(ex.packets, ex.flows, ex.frame, log)
