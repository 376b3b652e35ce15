"""Context features (`uavcas.flows.context`) on hand-built captures: each feature on a case whose
value is worked out by hand, and the invariances (row order, renamed addresses)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from helpers.capture_tables import HOP_S, IPS, POINTS, T0, send, table
from uavcas.flows.assemble import FlowConfig, assemble
from uavcas.flows.context import context_frame
from uavcas.flows.transmissions import transmissions
from uavcas.schema import CONTEXT_FEATURES

SYN, ACK, PSH, FIN = 0x02, 0x10, 0x08, 0x01


def fetch(t, path, sport, id0=0, answered=True) -> list[dict]:
    """Client path[0]'s host fetches from path[-1]'s host: handshake, two 1000-byte segments,
    ACK, FIN exchange. Unanswered: the SYN and its retransmission 1 s later, nothing back."""
    c, s = path[0], path[-1]
    back = path[::-1]
    up = dict(src=c, dst=s, sport=sport, dport=80)
    down = dict(src=s, dst=c, sport=80, dport=sport)
    if not answered:
        return send(t, path, flags=SYN, seq=100, id=id0, **up) + send(t + 1, path, flags=SYN, seq=100, id=id0 + 1, **up)
    d = HOP_S * (len(path) - 1)  # one way
    return (send(t, path, flags=SYN, seq=100, id=id0, **up)
            + send(t + d + 0.001, back, flags=SYN | ACK, seq=500, id=0, **down)
            + send(t + 2 * d + 0.002, path, flags=ACK, seq=101, id=id0 + 1, **up)
            + send(t + 2 * d + 0.010, back, flags=ACK | PSH, seq=501, id=id0 + 2, payload=1000, **down)
            + send(t + 2 * d + 0.020, back, flags=ACK | PSH, seq=1501, id=id0 + 3, payload=1000, **down)
            + send(t + 3 * d + 0.030, path, flags=ACK, seq=101, id=id0 + 4, **up)
            + send(t + 3 * d + 0.040, back, flags=FIN | ACK, seq=2501, id=id0 + 5, **down)
            + send(t + 4 * d + 0.050, path, flags=FIN | ACK, seq=101, id=id0 + 6, **up))


def ctx(obs, ips=IPS) -> pd.DataFrame:
    """Context columns keyed by (initiator port, first packet time) so tests can pick a flow."""
    p = table(obs, ips)
    fl = assemble(p, FlowConfig())
    c = context_frame(p, fl)
    first = fl.first
    port = np.where(fl.fwd[fl.starts[:-1]], p["sport"][first], p["dport"][first])
    c.index = pd.MultiIndex.from_arrays([port, np.round((p["ts_ns"][first] / 1e9 - T0), 3)], names=["port", "t"])
    return c


def flow(c: pd.DataFrame, port: int) -> pd.Series:
    """The flow of initiator port `port` that opened first (its SYN)."""
    return c.xs(port, level="port").iloc[0]


def test_columns_and_empty():
    c = ctx(fetch(0.5, ["a", "r", "b"], 40000))
    assert tuple(c.columns) == CONTEXT_FEATURES and c.dtypes.eq(np.float64).all()
    p = table([])
    empty = context_frame(p, assemble(p, FlowConfig()))
    assert tuple(empty.columns) == CONTEXT_FEATURES and len(empty) == 0
    with pytest.raises(ValueError, match="window"):
        context_frame(p, assemble(p, FlowConfig()), window_s=0)


def test_path_length_delay_and_round_trip():
    f = flow(ctx(fetch(0.5, ["a", "r", "b"], 40000)), 40000)
    assert f["ctx_path_len_mean"] == 3 and f["ctx_delay_ms"] == pytest.approx(2.0)
    # SYN enters at s-a at 0.5; the SYN-ACK leaves s-b 3 ms later and reaches s-a 2 ms after that
    assert f["ctx_rtt_ms"] == pytest.approx(5.0)
    zero = ["ctx_lost_frac", "ctx_offhome_frac", "ctx_ttl_off_frac", "ctx_ttl_levels", "ctx_neardup_frac",
            "ctx_retx_frac", "ctx_seq_regress_frac"]
    assert (f[zero] == 0).all()


def test_transmissions_learn_home_switches():
    t = transmissions(table(fetch(0.5, ["a", "r", "b"], 40000)))
    assert len(t.n_points) == 8 and (t.n_points == 3).all() and t.reached.all()
    assert sorted(POINTS[h] for h in t.home) == ["s-a", "s-b"]


def test_packet_that_never_reaches_its_destination_switch():
    obs = fetch(0.5, ["a", "r", "b"], 40000)
    obs = [o for o in obs if not (o["id"] == 2 and o["at"] == "a")]  # B's first data segment: lost on r -> a
    c = ctx(obs)
    # captured at s-b (it saw every packet; s-a missed one); the connection is one flow (8 packets)
    f = flow(c, 40000)
    assert f["ctx_lost_frac"] == pytest.approx(1 / 8)
    # a lost packet's path is how far it got: the lost segment was seen at s-b and s-r (2 switches,
    # 1 ms), the other seven at all three (2 ms)
    assert f["ctx_path_len_mean"] == pytest.approx(23 / 8) and f["ctx_delay_ms"] == pytest.approx(15 / 8)
    assert f["ctx_dst_lost_out_frac"] == pytest.approx(1 / 4) and f["ctx_src_lost_in_frac"] == pytest.approx(1 / 4)
    assert f["ctx_dst_lost_in_frac"] == 0 and f["ctx_net_lost_frac"] == pytest.approx(1 / 8)


def test_replayed_copy_enters_elsewhere_with_rewritten_fields():
    obs = fetch(0.5, ["a", "r", "b"], 40000)
    orig = next(o for o in obs if o["id"] == 2 and o["at"] == "b")  # B's first data segment
    copy = {k: v for k, v in orig.items() if k not in ("t", "at")}
    copy.update(ttl=59, seq=orig["seq"] + 1)  # TTL - 5, seq + k: the replayer's rewrite
    obs += send(0.528, ["x", "r", "a"], **copy)  # injected at the attacker's switch, before the FINs
    # s-a and s-r saw one packet more than s-b: captured at s-a; 9 packets (the connection and the copy)
    f = flow(ctx(obs), 40000)
    assert f["ctx_offhome_frac"] == pytest.approx(1 / 9) and f["ctx_ttl_off_frac"] == pytest.approx(1 / 9)
    assert f["ctx_ttl_levels"] == 1 and f["ctx_neardup_frac"] == pytest.approx(1 / 9)
    assert f["ctx_seq_regress_frac"] == pytest.approx(1 / 9) and f["ctx_retx_frac"] == 0
    # per host: of the transmissions sourced by or sent to B in that window, one entered off-home
    assert f["ctx_dst_offhome_frac"] == pytest.approx(1 / 9) and f["ctx_dst_ttl_off_frac"] == pytest.approx(1 / 9)


def test_retransmission_is_not_a_copy():
    obs = fetch(0.5, ["a", "r", "b"], 40000)
    orig = [o for o in obs if o["id"] == 2]
    obs += [{**o, "t": o["t"] + 0.02, "id": 9} for o in orig]  # same segment, new IP id, same TTL
    f = flow(ctx(obs), 40000)
    assert f["ctx_retx_frac"] == pytest.approx(1 / 9)  # the connection's 8 packets and the retransmission
    assert f["ctx_neardup_frac"] == 0 and f["ctx_seq_regress_frac"] == 0 and f["ctx_ttl_levels"] == 0


def test_blackholed_host_against_its_earlier_windows():
    path = ["a", "r", "b"]
    obs = fetch(0.5, path, 40000) + fetch(5.5, path, 40001, id0=10) + fetch(10.5, path, 40002, id0=20, answered=False)
    c = ctx(obs)
    early, late = flow(c, 40000), flow(c, 40002)
    assert early["ctx_dst_unanswered_frac"] == 0 and early["ctx_dst_unanswered_shift"] == 0
    assert early["ctx_dst_out_share"] == pytest.approx(0.5)  # B sent 4 of the 8 transmissions
    assert late["ctx_dst_unanswered_frac"] == 1 and late["ctx_dst_unanswered_shift"] == 1
    assert late["ctx_dst_out_share"] == 0 and late["ctx_dst_out_share_shift"] == pytest.approx(-0.5)
    # earlier windows: one connection, one flow each; now one attempt: as shares of the window's
    # flows (one of one) and as a log ratio to the past (as many flows as before)
    assert late["ctx_dst_flow_share"] == 1 and early["ctx_dst_flow_share"] == 1
    assert late["ctx_dst_flows_log_ratio"] == pytest.approx(0.0)
    assert late["ctx_retx_frac"] == pytest.approx(0.5) and late["ctx_rtt_ms"] == -1
    assert late["ctx_dst_rtt_ms"] == -1 and late["ctx_dst_rtt_shift_ms"] == 0  # no round trip to compare
    assert late["ctx_net_unanswered_frac"] == 1 and early["ctx_net_unanswered_frac"] == 0
    # a closed connection's flow is no unanswered request
    assert (c["ctx_src_unanswered_frac"].xs(40000, level="port") == 0).all()


def test_detour_adds_a_switch_against_earlier_windows():
    obs = (fetch(0.5, ["a", "r", "b"], 40000) + fetch(5.5, ["a", "r", "b"], 40001, id0=10)
           + fetch(10.5, ["a", "r", "x", "b"], 40002, id0=20))
    c = ctx(obs)
    f = flow(c, 40002)
    assert f["ctx_path_len_mean"] == 4 and f["ctx_dst_path_len_shift"] == 1 and f["ctx_src_path_len_shift"] == 1
    assert f["ctx_delay_ms"] == pytest.approx(3.0) and f["ctx_dst_delay_shift_ms"] == pytest.approx(1.0)
    assert f["ctx_rtt_ms"] == pytest.approx(7.0) and f["ctx_dst_rtt_shift_ms"] == pytest.approx(2.0)
    assert flow(c, 40001)["ctx_dst_path_len_shift"] == 0
    assert f["ctx_net_path_len_mean"] == 4
    # the host pair's windows, and the flow itself against the pair's earlier windows
    assert f["ctx_pair_path_len_mean"] == 4 and f["ctx_pair_path_len_shift"] == 1 and f["ctx_pair_flow_share"] == 1
    assert f["ctx_path_len_shift"] == 1 and f["ctx_delay_shift_ms"] == pytest.approx(1.0)
    assert f["ctx_rtt_shift_ms"] == pytest.approx(2.0) and f["ctx_pair_rtt_shift_ms"] == pytest.approx(2.0)
    first = flow(c, 40000)
    assert first["ctx_path_len_shift"] == 0 and first["ctx_rtt_shift_ms"] == 0  # no earlier window to compare


def test_shift_uses_the_median_of_earlier_windows_only():
    paths = [["a", "r", "b"], ["a", "r", "b"], ["a", "r", "x", "b"], ["a", "r", "b"]]
    c = ctx([o for k, p in enumerate(paths) for o in fetch(0.5 + 5 * k, p, 40000 + k, id0=10 * k)])
    # earlier windows: 3, 3, 4 switches: median 3
    assert flow(c, 40003)["ctx_dst_path_len_shift"] == 0
    assert flow(c, 40000)["ctx_dst_path_len_shift"] == 0  # first window: nothing earlier


def test_destination_that_never_sends_has_no_home():
    obs = send(0.5, ["a", "r"], "a", "x", flags=SYN, seq=1, id=1, sport=40000, dport=80)
    f = flow(ctx(obs), 40000)
    assert f["ctx_lost_frac"] == 0  # unknown home: cannot tell it was lost


def test_invariant_to_row_order_and_address_names():
    obs = (fetch(0.5, ["a", "r", "b"], 40000) + fetch(5.5, ["a", "r", "x", "b"], 40001, id0=10)
           + fetch(10.5, ["a", "r", "b"], 40002, id0=20, answered=False))
    base = ctx(obs)
    shuffled = [obs[i] for i in np.random.default_rng(0).permutation(len(obs))]
    pd.testing.assert_frame_equal(ctx(shuffled), base)
    renamed = {"a": "192.168.7.9", "b": "10.0.0.1", "r": "172.16.0.2", "x": "10.9.9.9"}
    pd.testing.assert_frame_equal(ctx(obs, renamed), base)


def test_flood_lost_before_leaving_the_attackers_switch():
    """A flood whose SYNs mostly die at the attacker's own switch (the victim out of reach) still
    has a path (1 switch: how far they got) and no delay; the victim's share of the window's
    flows does not grow with the flood's rate."""
    syn = lambda k, path: send(0.5 + 0.01 * k, path, "x", "b", flags=SYN, seq=k, id=k, sport=50000 + k, dport=80)  # noqa: E731
    obs = fetch(0.2, ["a", "r", "b"], 40000)  # B is home at s-b: it answers the fetch
    flood = [o for k in range(4) for o in syn(k, ["x", "r", "b"] if k == 0 else ["x"])]
    c = ctx(obs + flood)
    lost = flow(c, 50001)
    assert lost["ctx_lost_frac"] == 1 and lost["ctx_path_len_mean"] == 1 and lost["ctx_delay_ms"] == -1
    reached = flow(c, 50000)
    assert reached["ctx_lost_frac"] == 0 and reached["ctx_path_len_mean"] == 3
    assert reached["ctx_delay_ms"] == pytest.approx(2.0)
    # window 0: the fetch, the lone flows its close leaves, and the 4 SYN flows; x is in 4 of them
    n_window = len(c)
    assert lost["ctx_src_flow_share"] == pytest.approx(4 / n_window)
    assert lost["ctx_pair_flow_share"] == pytest.approx(4 / n_window)
    twice = ctx(obs + flood + [o for k in range(4, 8) for o in syn(k, ["x"])])
    assert flow(twice, 50001)["ctx_src_flow_share"] == pytest.approx(8 / len(twice))


def mavlink(t, path, k, lost_after=None, ip_id=None) -> list[dict]:
    """Datagram k of a 10 Hz MAVLink stream a -> b (UDP 14555 -> 14550, 40 bytes): seen along
    `path`, up to switch `lost_after` when it is lost on the next hop."""
    stop = path.index(lost_after) + 1 if lost_after else len(path)
    return send(t + 0.1 * k, path[:stop], "a", "b", sport=14555, dport=14550, proto=17, payload=40,
                id=k + 1 if ip_id is None else ip_id)


def test_udp_stream_gets_path_length_delay_and_loss_as_tcp():
    """Transmission-based context (path length, delay, loss) is protocol-agnostic: a UDP stream
    through a relay, one datagram lost on the relay's hop to b, and the ground station's 1 Hz
    heartbeats back (b must send for its switch to be known: a host that never sends has no home,
    and what is sent to it counts as reached)."""
    obs = [o for k in range(20) for o in mavlink(0.5, ["a", "r", "b"], k, lost_after="r" if k == 7 else None)]
    obs += [o for k in range(2) for o in send(0.55 + k, ["b", "r", "a"], "b", "a", sport=14550, dport=14555,
                                                proto=17, payload=21, id=900 + k)]
    c = ctx(obs)
    assert len(c) == 1  # one flow: the 5-tuple of the stream, both ways
    f = c.iloc[0]
    assert f["ctx_path_len_mean"] == pytest.approx((19 * 3 + 2 + 2 * 3) / 22)
    assert f["ctx_delay_ms"] == pytest.approx((19 * 2 + 1 + 2 * 2) / 22)
    assert f["ctx_lost_frac"] == pytest.approx(1 / 22) and f["ctx_pair_lost_frac"] == pytest.approx(1 / 22)
    assert f["ctx_rtt_ms"] == -1  # no handshake: round trip is TCP's
    tcp_only = ["ctx_neardup_frac", "ctx_retx_frac", "ctx_seq_regress_frac"]
    assert (f[tcp_only] == 0).all()


def test_udp_stream_with_ip_id_0_pairs_its_identical_datagrams_per_switch():
    """An unconnected UDP socket sends IP id 0 (DF set): the stream's datagrams share every header
    field a switch keeps; the k-th observation at each switch is the k-th datagram."""
    obs = [o for k in range(20) for o in mavlink(0.5, ["a", "r", "b"], k, ip_id=0)]
    t = transmissions(table(obs))
    assert len(t.n_points) == 20 and (t.n_points == 3).all() and t.reached.all()
    assert t.delay_ms == pytest.approx(np.full(20, 2.0))
