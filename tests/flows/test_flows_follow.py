"""The packet follower on hand-built packet tables and a four-switch plan.

Topology (window 0): uav0 - uav1 - bs0, uav0 - uav2, uav2 - bs0; routes send uav0 <-> bs0
through uav1. Window 1 drops uav0 - uav1, so the same traffic goes through uav2.
"""

from __future__ import annotations

import numpy as np
import pytest

from helpers.followgen import D_MS, IPS, PLAN, POINTS, TL, TL_NH
from helpers.followgen import send as _send
from helpers.followgen import table as _table
from helpers.pcapgen import T0, udp, write
from uavcas.flows.follow import STAMP_SKEW_S, Timeline, follow, follow_run
from uavcas.rundir import ForwardingEpoch, RunDir


def _paths(f, table):
    return {p: f.path(p)[0] for p in range(f.n_packets)}


def test_multi_hop_delivery_one_pid_hops_in_order():
    rows = _send(0.5, ["uav0", "uav1", "bs0"]) + _send(0.7, ["bs0", "uav1", "uav0"], id=9)
    rows.reverse()  # the table's row order must not matter
    t = _table(rows)
    f = follow(t, TL)
    assert f.n_packets == 2
    assert f.path(0)[0] == ["s-uav0", "s-uav1", "s-bs0"] and f.path(1)[0] == ["s-bs0", "s-uav1", "s-uav0"]
    for p in range(2):
        rows_p = np.flatnonzero(f.pid == p)
        assert sorted(f.hop[rows_p].tolist()) == [0, 1, 2]
        assert f.hop[rows_p][np.argsort(t["ts_s"][rows_p])].tolist() == [0, 1, 2]
    assert f.delivered.all() and len(f.losses) == 0
    c = f.crossings()
    assert len(c) == 4 and np.allclose(c.t_to - c.t_from, D_MS / 1000, atol=1e-6)


def test_loss_on_a_given_hop_is_located():
    rows = _send(1.0, ["uav0", "uav1", "bs0"], id=1)[:2] + _send(1.2, ["uav0", "uav1", "bs0"], id=2)[:1]
    rows += _send(6.0, ["uav0", "uav2", "bs0"], id=3)[:2]  # window 1: the route goes through uav2
    f = follow(_table(rows), TL)
    assert f.n_packets == 3 and not f.delivered.any()
    got = sorted((POINTS[a], POINTS[b], int(w)) for a, b, w in
                 zip(f.losses.from_point, f.losses.to_point, f.losses.window))
    assert got == [("s-uav0", "s-uav1", 0), ("s-uav1", "s-bs0", 0), ("s-uav2", "s-bs0", 1)]


def test_identical_looking_packets_never_merge():
    # Unconnected UDP with DF carries IP id 0: same header, same length, 1 ms apart, 5 ms hops,
    # so both are in flight on the same hop at once.
    a = _send(2.0, ["uav0", "uav1", "bs0"])
    b = _send(2.001, ["uav0", "uav1", "bs0"])
    f = follow(_table(a + b), TL)
    assert f.n_packets == 2
    for p in range(2):
        pts, times = f.path(p)
        assert pts == ["s-uav0", "s-uav1", "s-bs0"]
        assert np.allclose(np.diff(times), D_MS / 1000, atol=1e-6)
    assert f.delivered.all()


def test_identical_packets_first_lost_second_not_taken_for_it():
    a = _send(2.0, ["uav0", "uav1", "bs0"])[:2]  # lost on uav1 -> bs0
    b = _send(2.1, ["uav0", "uav1", "bs0"])
    f = follow(_table(a + b), TL)
    assert f.n_packets == 2
    assert f.path(0)[0] == ["s-uav0", "s-uav1"] and f.path(1)[0] == ["s-uav0", "s-uav1", "s-bs0"]
    assert np.allclose(np.diff(f.path(1)[1]), D_MS / 1000, atol=1e-6)
    assert [(POINTS[x], POINTS[y]) for x, y in zip(f.losses.from_point, f.losses.to_point)] == [("s-uav1", "s-bs0")]


def test_retransmissions_are_separate_packets():
    seg = {"proto": 6, "sport": 40000, "dport": 80, "seq": 1000, "flags": 0x18, "len": 1514}
    rows = _send(3.0, ["uav0", "uav1", "bs0"], id=11, **seg)[:2]  # the original, lost on the last hop
    rows += _send(3.2, ["uav0", "uav1", "bs0"], id=12, **seg)  # the retransmission: new IP id
    rows += _send(3.5, ["uav0", "uav1", "bs0"], id=12, **seg)  # identical header again (worst case)
    f = follow(_table(rows), TL)
    assert f.n_packets == 3
    assert [len(f.path(p)[0]) for p in range(3)] == [2, 3, 3]
    assert f.delivered.tolist() == [False, True, True]


def test_flood_with_reused_ports_and_ids_keeps_every_packet():
    rng = np.random.default_rng(7)
    syn = {"proto": 6, "sport": 3000, "dport": 80, "seq": 42, "flags": 0x02, "id": 7, "len": 54}
    rows, lost = [], []
    for k in range(60):  # 1 ms apart, 5 ms hops: five packets in flight per hop, all alike
        obs = _send(4.0 + k * 0.001, ["uav2", "bs0", "uav1"], **syn)
        late = 0.0
        for o in obs[1:]:
            late += float(rng.uniform(0, 0.0002))  # scheduling jitter, order kept
            o["t"] += late
        if k % 7 == 3:
            obs = obs[:2]
            lost.append(k)
        rows += obs
    f = follow(_table(rows), TL)
    assert f.n_packets == 60
    for p in range(60):
        pts, times = f.path(p)
        assert len(set(pts)) == len(pts) and np.all(np.diff(times) < 0.0053) and np.all(np.diff(times) > 0.00499)
    assert sorted(f.losses.pid.tolist()) == lost  # pids follow first-seen order: pid k is the k-th SYN
    assert {(POINTS[a], POINTS[b]) for a, b in zip(f.losses.from_point, f.losses.to_point)} == {("s-bs0", "s-uav1")}


def test_unknown_destination_and_disconnected_switch():
    rows = _send(1.0, ["uav0", "uav1"])
    for r in rows:
        r["dst"] = "10.200.0.1"  # not a node: no destination, no loss claimed
    rows += [{"t": 6.0, "at": "uav1", "src": "uav1", "dst": "uav0"}]  # window 1: uav1 reaches uav0 via bs0
    rows += [{"t": 6.5, "at": "uav0", "src": "uav0", "dst": "uav1", "id": 5}]
    f = follow(_table(rows), TL)
    assert f.n_packets == 3
    by_from = {POINTS[a]: int(b) for a, b in zip(f.losses.from_point, f.losses.to_point)}
    assert by_from == {"s-uav1": POINTS.index("s-bs0"), "s-uav0": POINTS.index("s-uav2")}


def test_logged_forwarding_overrides_the_plan():
    # The run logged a detour (as a wormhole would install): uav0 -> bs0 via uav2 in window 0.
    nh = {"uav0": {"bs0": "uav2", "uav1": "uav1", "uav2": "uav2"}, "uav2": {"bs0": "bs0", "uav0": "uav0"},
          "bs0": {"uav0": "uav2"}, "uav1": {"uav0": "uav0"}}
    tl = Timeline.from_epochs(PLAN, [ForwardingEpoch(t_begin_unix=T0, t_unix=T0, window=0, next_hop=nh)])
    rows = _send(1.0, ["uav0", "uav2", "bs0"], id=1)[:2]
    f_log, f_plan = follow(_table(rows), tl), follow(_table(rows), TL)
    assert f_log.n_packets == 1 and f_log.losses.to_point.tolist() == [POINTS.index("s-bs0")]
    assert f_plan.n_packets == 1 and f_plan.losses.to_point.tolist() == [POINTS.index("s-bs0")]
    rows = _send(1.0, ["uav0", "uav1", "bs0"], id=2)[:2]  # uav1 held no entry for bs0: dropped there, no next hop
    f = follow(_table(rows), tl)
    assert f.n_packets == 1 and f.losses.to_point.tolist() == [-1] and f.losses.from_point.tolist() == [1]


def test_a_logged_wormhole_detour_gives_the_victims_frames_their_next_hops_and_only_them():
    # The table sends uav1 <-> bs0 over their direct link; the detour carries uav1's frames to
    # bs0 (and bs0's back) through uav0 and uav2 on alias MACs, outside the table
    # (network.forwarding). A medium run's audit, reading the table alone, chained detoured
    # frames from the first switch straight to the last and left the middle ones orphaned.
    path = ["uav1", "uav0", "uav2", "bs0"]
    tl = Timeline.from_epochs(PLAN, [
        ForwardingEpoch(t_begin_unix=T0, t_unix=T0, window=0, next_hop=TL_NH[0]),
        ForwardingEpoch(t_begin_unix=T0 + 2.0, t_unix=T0 + 2.01, window=0, next_hop=TL_NH[0],
                        detours={"uav1>bs0": path}),
        ForwardingEpoch(t_begin_unix=T0 + 4.0, t_unix=T0 + 4.01, window=0, next_hop=TL_NH[0])])
    ix = {n: k for k, n in enumerate(tl.nodes)}

    def hops(t, at, src, dst, with_src=True):
        now, nxt = tl.hops(np.array([T0 + t]), np.array([ix[at]]), np.array([ix[dst]]),
                           np.array([ix[src]]) if with_src else None)
        return tl.nodes[now[0]] if now[0] >= 0 else None, tl.nodes[nxt[0]] if nxt[0] >= 0 else None

    assert hops(1.0, "uav1", "uav1", "bs0") == ("bs0", "bs0")  # before the detour: the table
    assert hops(3.0, "uav1", "uav1", "bs0") == ("uav0", "uav0")
    assert hops(3.0, "uav0", "uav1", "bs0") == ("uav2", "uav2") and hops(3.0, "uav2", "uav1", "bs0") == ("bs0", "bs0")
    assert hops(3.0, "bs0", "bs0", "uav1") == ("uav2", "uav2") and hops(3.0, "uav0", "bs0", "uav1") == ("uav1", "uav1")
    assert hops(2.005, "uav1", "uav1", "bs0") == ("bs0", "uav0")  # installing: either
    assert hops(4.005, "uav1", "uav1", "bs0") == ("uav0", "bs0")  # removing: either
    assert hops(3.0, "uav0", "uav0", "bs0") == hops(1.0, "uav0", "uav0", "bs0")  # another source: the table
    assert hops(3.0, "uav1", "uav1", "bs0", with_src=False) == ("bs0", "bs0")


def test_follow_run_reads_captures_and_forwarding(tmp_path):
    rd = RunDir(tmp_path)
    (tmp_path / "pcap").mkdir()
    rd.plan_json.write_text(PLAN.to_json())
    epochs = [ForwardingEpoch(t_begin_unix=T0 + w.t_s, t_unix=T0 + w.t_s, window=w.index,
                              next_hop=TL_NH[w.index]) for w in PLAN.windows]
    rd.forwarding_jsonl.write_text("".join(e.model_dump_json() + "\n" for e in epochs))
    for k, node in enumerate(["uav0", "uav1", "bs0"]):
        pk = [udp(0.2 + 0.005 * k, IPS["uav0"], IPS["bs0"], 5000, 6000, size=50),
              udp(0.4 + 0.005 * k, IPS["uav0"], IPS["bs0"], 5000, 6000, size=50)]
        write(tmp_path / "pcap" / f"s-{node}.pcap", pk)
    table, f = follow_run(tmp_path)
    assert len(table) == 6 and f.n_packets == 2 and f.delivered.all()
    assert [f.path(p)[0] for p in range(2)] == [["s-uav0", "s-uav1", "s-bs0"]] * 2


def test_empty_table():
    f = follow(_table([]), TL)
    assert f.n_packets == 0 and len(f.losses) == 0 and len(f.crossings()) == 0




@pytest.mark.parametrize("max_hop_s", [0.5, 2.0])
def test_gap_longer_than_a_hop_splits(max_hop_s):
    rows = _send(1.0, ["uav0", "uav1", "bs0"])[:1] + [{"t": 1.0 + 1.0, "at": "uav1", "src": "uav0", "dst": "bs0"}]
    f = follow(_table(rows), TL, max_hop_s=max_hop_s)
    assert f.n_packets == (2 if max_hop_s < 1.0 else 1)


def _busy(t0, n, frm="uav0", length=1514):
    """n frames of another flow that entered `frm` -> uav1 together before t0 - 5 ms and leave
    back to back, seen at uav1 from t0 (s from T0): they keep that port busy."""
    gap = length * 8 / 24e6  # the links' planned 24 Mbit/s
    return [r for k in range(n) for r in (
        {"t": t0 - D_MS / 1000 - 0.0005, "at": frm, "src": frm, "dst": "uav1", "id": 100 + k, "len": length},
        {"t": t0 + k * gap, "at": "uav1", "src": frm, "dst": "uav1", "id": 100 + k, "len": length})]


SYNACK = {"proto": 6, "sport": 80, "dport": 40000, "seq": 7, "flags": 0x12, "id": 0, "len": 66}


def test_identical_copies_leave_a_queued_link_in_the_order_they_entered():
    # A SYN-ACK (IP id 0) and its retransmission, byte for byte, 2 ms apart on uav0, queued
    # behind 2 ms of other frames at uav1: the first copy leaves at 7 ms, the second right behind
    # it. The step closest to the planned 5 ms is the second copy's: FIFO order is the evidence.
    a, b = _send(1.0, ["uav0", "uav1", "bs0"], **SYNACK), _send(1.002, ["uav0", "uav1", "bs0"], **SYNACK)
    a[1]["t"], a[2]["t"] = 1.007, 1.012
    b[1]["t"], b[2]["t"] = 1.00703, 1.01203
    f = follow(_table(a + b + _busy(1.005, 4)), TL)
    synack = [p for p in range(f.n_packets) if len(f.path(p)[0]) == 3]
    assert len(synack) == 2
    got = sorted([round(float(t) - T0, 5) for t in f.path(p)[1]] for p in synack)
    assert got == [[1.0, 1.007, 1.012], [1.002, 1.00703, 1.01203]]
    assert not f.revisit.any()


def test_a_copy_lost_on_the_link_does_not_take_the_next_copys_observation():
    # the first copy is lost on uav0 -> uav1; nothing kept that port busy (uav1 was busy with
    # bs0's frames: another port), so the frame seen at uav1 at 7 ms (5 ms after the second copy)
    # is the second copy's, not the first's 2 ms late
    a = _send(1.0, ["uav0", "uav1", "bs0"], **SYNACK)[:1]
    b = _send(1.002, ["uav0", "uav1", "bs0"], **SYNACK)
    f = follow(_table(a + b + _busy(1.005, 4, frm="bs0")), TL)
    synack = [p for p in range(f.n_packets) if f.path(p)[0][0] == "s-uav0"]
    assert len(synack) == 2 and f.delivered[synack].tolist() == [False, True]
    assert f.n_packets == 6
    assert np.allclose(np.diff(f.path(synack[1])[1]), D_MS / 1000, atol=1e-6)
    assert [(POINTS[x], POINTS[y]) for x, y in zip(f.losses.from_point, f.losses.to_point)] == [("s-uav0", "s-uav1")]


def test_a_frame_that_comes_back_to_a_switch_is_a_loop_not_a_new_packet():
    # while uav1's table is being changed it sends bs0's traffic back to uav0, which sends it
    # to uav1 again: one packet seen at uav0, uav1, uav0, uav1, bs0
    loop = {**TL_NH[0], "uav1": {**TL_NH[0]["uav1"], "bs0": "uav0"}}
    tl = Timeline.from_epochs(PLAN, [ForwardingEpoch(t_begin_unix=T0, t_unix=T0, window=0, next_hop=TL_NH[0]),
                                     ForwardingEpoch(t_begin_unix=T0 + 1.001, t_unix=T0 + 1.001, window=0,
                                                     next_hop=loop),
                                     ForwardingEpoch(t_begin_unix=T0 + 1.012, t_unix=T0 + 1.012, window=0,
                                                     next_hop=TL_NH[0])])
    rows = [{"t": 1.0 + 0.005 * k, "at": n, "src": "uav0", "dst": "bs0", "id": 3}
            for k, n in enumerate(["uav0", "uav1", "uav0", "uav1", "bs0"])]
    f = follow(_table(rows), tl)
    assert f.n_packets == 1 and f.delivered.tolist() == [True] and len(f.losses) == 0
    assert f.path(0)[0] == ["s-uav0", "s-uav1", "s-uav0", "s-uav1", "s-bs0"]
    assert f.revisit[np.argsort(f.hop)].tolist() == [False, False, True, True, False]
    assert f.crossings().revisit.tolist() == [False, True, True, False]
    # without the loop in the tables, the frame back at uav0 is a new transmission, not a loop
    f = follow(_table(rows), TL)
    assert not f.revisit.any() and f.n_packets == 2


def test_fifo_orders_copies_on_one_link_not_across_links():
    # uav1 -> bs0 at 0.2 Mbit/s, kept busy by another flow: a copy may wait there up to ~1 s. The
    # first copy is lost on it; the retransmission, 0.9 s later in window 1, goes via uav2. Its
    # arrival at bs0 is 5 ms after uav2, not a 0.9 s wait on the other link: FIFO says nothing
    # about two links, and the shorter queue wait is the one to believe.
    w0 = PLAN.windows[0]
    slow = [lk.model_copy(update={"rate_mbps": 0.2}) if {lk.a, lk.b} == {"uav1", "bs0"} else lk for lk in w0.links]
    plan = PLAN.model_copy(update={"windows": [w0.model_copy(update={"links": slow}), PLAN.windows[1]]})
    gap = 1514 * 8 / 0.2e6
    busy = [{"t": t, "at": at, "src": "uav1", "dst": "bs0", "id": 100 + k, "len": 1514}
            for k in range(16) for at, t in (("uav1", 4.03), ("bs0", 4.04 + k * gap))]
    a = _send(4.1, ["uav0", "uav1", "bs0"], **SYNACK)[:2]
    b = _send(5.0, ["uav0", "uav2", "bs0"], **SYNACK)
    f = follow(_table(a + b + busy), Timeline.from_plan(plan, T0))
    paths = sorted(f.path(p)[0] for p in range(f.n_packets) if f.path(p)[0][0] == "s-uav0")
    assert paths == [["s-uav0", "s-uav1"], ["s-uav0", "s-uav2", "s-bs0"]]


def test_a_lost_copy_is_judged_at_the_rate_the_port_held():
    # a jammer may slow uav0 -> uav1 to 0.2 Mbit/s in window 0 (the plan's override), but the run
    # says the port held its 24 Mbit/s then: the one frame ahead of the first copy kept the port
    # busy for 0.5 ms, not 60 ms, so that copy cannot have waited 2 ms: it was lost
    from uavcas.twin.model import LinkOverride

    jam = LinkOverride(attack_id="jamming-0", src="uav0", dst="uav1", start_s=0.0, stop_s=5.0, interference_dbm=-60.0,
                       sinr_db=3.0, mcs=0, rate_mbps=0.2, delay_ms=D_MS, loss=0.0)
    plan = PLAN.model_copy(update={"windows": [PLAN.windows[0].model_copy(update={"link_overrides": [jam]}),
                                               PLAN.windows[1]]})
    a = _send(1.0, ["uav0", "uav1", "bs0"], **SYNACK)[:1]
    b = _send(1.002, ["uav0", "uav1", "bs0"], **SYNACK)
    table = _table(a + b + _busy(1.0054, 1))
    tl = Timeline.from_plan(plan, T0)
    synack = np.asarray(table["frame_len"]) == SYNACK["len"]

    def paths(f):
        return sorted([round(float(f._ts[r]) - T0, 4) for r in np.flatnonzero(synack & (f.pid == p))]
                      for p in np.unique(f.pid[synack]))

    assert paths(follow(table, tl, capacity=lambda i, j, a, b: (b - a) * 24e6)) == [[1.0], [1.002, 1.007, 1.012]]
    assert paths(follow(table, tl)) == [[1.0, 1.007, 1.012], [1.002]]  # judged at the plan's slowest rate


def test_two_stamps_out_of_forwarding_order_are_one_packet_in_forwarding_order():
    # the frame reached uav1 0.3 ms before uav0's capture stamped it (a TCP frame: no switch stamps
    # it on receipt); swapped within `STAMP_SKEW_S`, it is one packet crossing both hops
    seg = {"proto": 6, "sport": 40000, "dport": 80, "seq": 1000, "flags": 0x10, "len": 1514, "id": 4}
    rows = _send(1.0, ["uav0", "uav1", "bs0"], **seg)
    rows[0]["t"] = rows[1]["t"] + 0.0003
    f = follow(_table(rows), TL)
    assert f.n_packets == 1 and f.delivered.all() and len(f.losses) == 0
    pts, times = f.path(0)
    assert pts == ["s-uav0", "s-uav1", "s-bs0"]
    c = f.crossings()
    assert [(POINTS[a], POINTS[b]) for a, b in zip(c.from_point, c.to_point)] == [("s-uav0", "s-uav1"),
                                                                                 ("s-uav1", "s-bs0")]
    assert c.t_to[0] - c.t_from[0] == pytest.approx(-0.0003, abs=1e-6)
    # an order that is a forwarding step is never swapped, however close the stamps
    ok = _send(2.0, ["uav0", "uav1", "bs0"], d_s=0.0001, **{**seg, "id": 5})
    assert follow(_table(ok), TL).path(0)[0] == ["s-uav0", "s-uav1", "s-bs0"]


def test_only_tcp_stamps_within_stamp_skew_s_are_reordered():
    # a UDP frame carries no departure time (every switch stamps it on receipt), and stamps further
    # apart than STAMP_SKEW_S are not one frame's
    seg = {"proto": 6, "sport": 40000, "dport": 80, "seq": 1000, "flags": 0x10, "len": 1514, "id": 4}
    for hdr, skew in (({**seg, "proto": 17}, 0.0003), (seg, STAMP_SKEW_S + 0.001)):
        rows = _send(1.0, ["uav0", "uav1", "bs0"], **hdr)
        rows[0]["t"] = rows[1]["t"] + skew
        f = follow(_table(rows), TL)
        assert ["s-uav0", "s-uav1", "s-bs0"] not in [f.path(p)[0] for p in range(f.n_packets)]
