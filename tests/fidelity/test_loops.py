"""Loops and in-flight re-routes among the packets back at a switch (`fidelity.loops`), on the
follower's four-switch plan (`helpers.followgen`)."""

from __future__ import annotations

import numpy as np

from helpers.followgen import NAMES, PLAN, TL_NH
from helpers.followgen import table as _table
from helpers.pcapgen import T0
from uavcas.fidelity.loops import rerouted_in_flight
from uavcas.flows.follow import Timeline, follow
from uavcas.rundir import ForwardingEpoch

# the change at 1.010-1.020 s: uav1 now sends bs0's traffic back to uav0, and uav0 via uav2
NEW = {**TL_NH[0], "uav0": {**TL_NH[0]["uav0"], "bs0": "uav2"}, "uav1": {**TL_NH[0]["uav1"], "bs0": "uav0"}}
TL = Timeline.from_epochs(PLAN, [ForwardingEpoch(t_begin_unix=T0, t_unix=T0, window=0, next_hop=TL_NH[0]),
                                 ForwardingEpoch(t_begin_unix=T0 + 1.010, t_unix=T0 + 1.020, window=0,
                                                 next_hop=NEW)])


def _classify(path_times: list[tuple[str, float]]) -> tuple[bool, list[str]]:
    rows = [{"t": t, "at": at, "src": "uav0", "dst": "bs0", "id": 7} for at, t in path_times]
    table = _table(rows)
    f = follow(table, TL)
    assert f.n_packets == 1 and f.revisit.any()
    fine = rerouted_in_flight(f, np.arange(len(NAMES)), TL, np.array([0]))
    return bool(fine[0]), f.path(0)[0]


def test_a_frame_queued_across_the_change_and_sent_back_is_rerouted_not_looped():
    # uav0 -> uav1 by the old table, 25 ms in uav1's queue, then the new tables: back to uav0, on via uav2
    fine, path = _classify([("uav0", 1.000), ("uav1", 1.030), ("uav0", 1.035), ("uav2", 1.040), ("bs0", 1.045)])
    assert path == ["s-uav0", "s-uav1", "s-uav0", "s-uav2", "s-bs0"] and fine


def test_a_new_hop_then_an_old_one_is_a_loop():
    # uav1 updated, uav0 not yet: uav1 -> uav0 (new), uav0 -> uav1 (old), round again: only a
    # state mixing the two tables in a cycle does that (the update order the fabric avoids)
    fine, path = _classify([("uav1", 1.011), ("uav0", 1.016), ("uav1", 1.021), ("uav0", 1.026), ("uav2", 1.031),
                            ("bs0", 1.036)])
    assert path[:4] == ["s-uav1", "s-uav0", "s-uav1", "s-uav0"] and not fine


def test_a_revisit_with_no_change_under_way_is_a_loop():
    # the same round trip as the re-route, long after the change ended
    fine, _ = _classify([("uav0", 2.000), ("uav1", 2.030), ("uav0", 2.035), ("uav2", 2.040), ("bs0", 2.045)])
    assert not fine
