"""Family tests reuse the synthetic run directory of tests/labels (scapy pcaps + a typed attack log)."""

from __future__ import annotations

import pytest

from helpers.synth_run import T0, build_run


@pytest.fixture(scope="session")
def synth_run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("run") / "run-synth")


@pytest.fixture(scope="session")
def truth_ctx(synth_run_dir):
    """A TruthContext of the synthetic run (packets, follower, attack log, plan) and its flows."""
    from uavcas.flows import FlowConfig, extract_flows
    from uavcas.flows.follow import follow_run
    from uavcas.labels import read_attack_log
    from uavcas.labels.effects import TruthContext
    from uavcas.rundir import RunDir

    rd = RunDir(synth_run_dir)
    ex = extract_flows(rd.pcaps(), FlowConfig(view="5tuple"))
    plan = rd.read_plan()
    log = read_attack_log(rd.attacks_jsonl, plan, T0)
    _, followed = follow_run(rd.root, table=ex.packets)
    return TruthContext(ex.packets, log, followed, plan, T0)
