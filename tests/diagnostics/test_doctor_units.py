"""The doctor's verdict logic, without root: a saturated machine fails, the result as plain JSON."""

from __future__ import annotations

import json

import numpy as np

from helpers.contention import quiet
from uavcas.diagnostics.checks import Check, HopConfig, loss_check
from uavcas.diagnostics.doctor import DoctorResult
from uavcas.emulation.probe import Features

FEATS = Features(root=True, netns=True, netem=False, htb=True, tbf=True, nft=True, nft_bridge_numgen=True,
                 nfqueue=True, br_netfilter=True, cgroup=None)


def test_check_is_plain_json_booleans_and_floats():
    c = loss_check(0.05, 3000, [HopConfig(10, 1, 0.02), HopConfig(10, 1, 0.03)])  # bounds come from scipy
    assert type(c.ok) is bool and type(c.low) is float
    text = json.dumps(c.to_dict())
    assert '"ok": true' in text
    res = DoctorResult(FEATS, "htb-nft-nfqueue", [c, Check("x", "ms", 1, 1, np.float64(5.0), 0, 2)],
                       contention=quiet())
    d = json.loads(json.dumps(res.to_dict()))
    assert d["ok"] is False and [x["ok"] for x in d["checks"]] == [True, False]
    assert d["contention"]["level"] == "quiet" and d["warnings"] == []


def test_saturated_machine_fails_the_doctor_even_when_every_figure_passes():
    ok = Check("x", "ms", 1, 1, 1.0, 0, 2)
    assert DoctorResult(FEATS, "b", [ok], contention=quiet()).ok
    sat = DoctorResult(FEATS, "b", [ok], contention=quiet(runq_per_cpu=3.0))
    assert sat.saturated and not sat.ok and sat.warnings and "saturated" in sat.warnings[0]
    contended = DoctorResult(FEATS, "b", [ok], contention=quiet(psi_some_pct=60.0))
    assert contended.ok and "contended" in contended.warnings[0]
