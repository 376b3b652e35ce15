"""Jamming on real runs: 6 UAVs, 2 BSs, 6 windows, a 20 dBm ground jammer, alone and with a
blackhole (issue 24).

Checks: both runs' fidelity audits pass; the audit measured the jammed link segments against
the JAMMED plan (their planned loss is the override's, not the link's) and the random loss it
saw on them is the jammed plan's (pooled over the jammed segments, within the audit's sigma
tolerance, and far from the unjammed plan's); every flow labelled Jamming holds a jamming
packet and every jamming packet lies in a flow labelled Jamming; flows wholly outside the
jammer's window are not Jamming.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from helpers.audit_checks import assert_audit_passes
from uavcas.extract import extract_detailed
from uavcas.fidelity import read_fidelity
from uavcas.labels import read_attack_log
from uavcas.rundir import RunDir
from uavcas.testing.audited import run_audited
from uavcas.vocabulary import FAMILIES

pytestmark = [pytest.mark.root, pytest.mark.slow]
SEED = 7  # the jammer's [5.2, 17.2) s leaves 5 s before and 13 s after it in 30 s
CONFIGS = {
    "jamming": "jamming=20-6-2-image-logdist-adaptive-grid-30-95",
    "blackhole+jamming": "blackhole+jamming=20-6-2-image-logdist-adaptive-grid-30-95",
}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("jamming")
    out = {}
    for name, cfg in CONFIGS.items():  # one at a time: two emulations at once strain the audit
        d = base / name.replace("+", "_")
        run_audited([cfg, "--seed", str(SEED), "--windows", "6"], d, timeout_s=300)
        out[name] = (RunDir(d), extract_detailed(d))
    return out


# A jammed link is throttled to 66-650 kbit/s. Before the delay stage paced the links (issue 28,
# stop 27), its crossings came late under load (10 of the medium campaign's 12 jamming runs failed
# their p99 delay check) and this test was an expected failure; it passed in the last two fresh
# clones' suites and is asserted again.
@pytest.mark.parametrize("name", list(CONFIGS))
def test_fidelity_passes(runs, name):
    rd, _ = runs[name]
    info = rd.read_info()
    assert info.exit_status == 0, info
    assert_audit_passes(rd)


@pytest.mark.parametrize("name", list(CONFIGS))
def test_jammed_links_loss_on_the_wire_is_the_jammed_plans(runs, name):
    rd, _ = runs[name]
    plan, fid = rd.read_plan(), read_fidelity(rd.root)
    jam = {(w.index, o.src, o.dst): o for w in plan.windows for o in w.link_overrides}
    links = {(w.index, lk.a, lk.b): lk for w in plan.windows for lk in w.links}
    obs = exp = var = exp_clear = 0.0
    segments = 0
    for lw in fid.links:
        o = jam.get((lw.window, lw.src, lw.dst))
        if o is None or (lw.planned_loss, lw.planned_rate_mbps) != (o.loss, o.rate_mbps) or not lw.loss_offered:
            continue  # not jammed, or a segment of the window outside the jammer's span
        lk = links.get((lw.window, lw.src, lw.dst)) or links[(lw.window, lw.dst, lw.src)]
        assert (lk.loss, lk.rate_mbps) != (o.loss, o.rate_mbps)  # audited against the jammed plan
        segments += 1
        obs += lw.loss_drops
        exp += lw.loss_offered * o.loss
        var += lw.loss_offered * o.loss * (1 - o.loss)
        exp_clear += lw.loss_offered * lk.loss
    assert segments >= 4 and exp >= 20, (segments, exp)  # enough jammed traffic to judge
    sigma = (obs - exp) / math.sqrt(max(var, 1.0))
    assert abs(sigma) <= fid.tolerances.loss_sigma, (obs, exp, sigma)
    # and it is not the unjammed plan's loss
    assert obs > exp_clear + 5 * math.sqrt(max(exp_clear, 1.0)), (obs, exp_clear)


@pytest.mark.parametrize("name", list(CONFIGS))
def test_jamming_labels_and_packets_agree(runs, name):
    rd, ex = runs[name]
    df = ex.shard.frame
    k = FAMILIES.index("jamming")
    labelled = df[df.label_jamming]
    assert len(labelled) > 0
    assert all("jamming" in set(e) for e in labelled.seq_effect)  # each holds a jamming packet
    assert (labelled.attack_packets_jamming > 0).all()
    row_flow = ex.flows.packet_flow(len(ex.packets))
    labelled_flow = np.zeros(ex.flows.n_flows, dtype=bool)
    labelled_flow[df.flow_id.to_numpy()] = df.label_jamming.to_numpy()
    affected = np.flatnonzero(ex.truth.family == k)
    seen = affected[row_flow[affected] >= 0]
    assert seen.size > 0 and labelled_flow[row_flow[seen]].all()
    # packet-exact in time: jamming only on packets seen around the jammer's logged window
    (w,) = read_attack_log(rd.attacks_jsonl, rd.read_plan(), rd.read_info().t0_unix).of_family("jamming")
    ts = ex.packets["ts_s"][affected]
    assert ts.min() >= w.start_unix - 1.0 and ts.max() < w.stop_unix + 1.0
    outside = df[(df.last_ts < w.start_unix) | (df.first_ts >= w.stop_unix)]
    assert len(outside) > 0 and not outside.label_jamming.any()
