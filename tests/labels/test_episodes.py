"""Episodes (`uavcas.labels.episodes`, the window-host view) on a hand-built packet table: labels
of a victim hit by two families in one window, de-duplicated observations, hand-computed features."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.synth_run import IPS, make_plan
from uavcas.flows import FlowConfig, assemble, flow_frame
from uavcas.flows.packets import PacketTable, address_to_words, table_from_rows
from uavcas.flows.standards import episode_feature_columns
from uavcas.labels.effects import PacketTruth
from uavcas.labels.episodes import host_window_frame
from uavcas.schema import EFFECTS, FAMILIES

T0 = 1_700_000_000.0
POINTS = ("s-uav0", "s-uav1", "s-uav3", "s-bs0")
SYN, ACK, PSH = 0x02, 0x10, 0x08


def _table(obs: list[dict]) -> PacketTable:
    rows = []
    for k, o in enumerate(obs):
        shi, slo = address_to_words(IPS[o["src"]])
        dhi, dlo = address_to_words(IPS[o["dst"]])
        length = 54 + o.get("payload", 0)
        rows.append({"ts_ns": round(T0) * 10**9 + round(o["t"] * 1e9), "frame_len": length, "cap_len": length,
                     "ip_version": 4, "ip_len": length - 14, "src_hi": shi, "src_lo": slo, "dst_hi": dhi,
                     "dst_lo": dlo, "sport": o["sport"], "dport": o["dport"], "proto": 6, "tcp_flags": o["flags"],
                     "ttl": 64, "ip_id": o.get("id", k), "tcp_seq": 100, "ip_hdr_len": 20, "l4_hdr_len": 20,
                     "frame_index": k,
                     "point": POINTS.index(o["at"])})  # fmt: skip
    return table_from_rows(rows, POINTS)


def _case():
    """uav1 floods uav0 (3 SYNs in window 1, 1 in window 3) while bs0's 2 packets to uav0 in
    window 1 are blackholed; uav3 <-> bs0 exchange a SYN and a SYN-ACK in window 0, each seen
    at both switches. Per observation: (effect, family)."""
    obs, truth = [], []

    def add(effect, fam, **o):
        obs.append(o)
        truth.append((EFFECTS.index(effect), FAMILIES.index(fam) if fam else -1))

    for k in range(3):
        add("flood", "dos", t=6.0 + 0.1 * k, at="s-uav0", src="uav1", dst="uav0", sport=1000 + k, dport=80, flags=SYN)
    add("flood", "dos", t=16.0, at="s-uav0", src="uav1", dst="uav0", sport=1003, dport=80, flags=SYN)
    for k in range(2):
        add("blackhole", "blackhole", t=7.0 + 0.5 * k, at="s-uav0", src="bs0", dst="uav0", sport=80, dport=5000,
            flags=PSH | ACK, payload=100)
    for at in ("s-uav3", "s-bs0"):
        add("benign", None, t=1.0 + (at == "s-bs0") * 1e-4, at=at, src="uav3", dst="bs0", sport=6000, dport=80,
            flags=SYN)
        add("benign", None, t=1.01 + (at == "s-uav3") * 1e-4, at=at, src="bs0", dst="uav3", sport=80, dport=6000,
            flags=SYN | ACK)
    p = _table(obs)
    eff, fam = np.array(truth, dtype=np.int8).T
    return p, PacketTruth(eff.copy(), fam.copy())


@pytest.fixture(scope="module")
def episodes():
    p, truth = _case()
    fl = assemble(p, FlowConfig())
    ff = flow_frame(p, fl)
    df = host_window_frame(p, fl, ff, truth, make_plan(), T0)
    return df.set_index(["host", "window"])


def test_two_families_on_one_victim_in_one_window(episodes):
    v = episodes.loc[("uav0", 1)]
    assert v.label == "Blackhole+DoS" and v.label_blackhole and v.label_dos and not v.label_replay
    assert (v.packets, v.attack_packets, v.attack_packets_dos, v.attack_packets_blackhole) == (5, 5, 3, 2)
    assert v.label_source == "flood-packets+blackhole-drops"
    # the next flood window holds the flood only; the attacker and the blackholed sender get one family
    assert episodes.loc[("uav0", 3)].label == "DoS" and episodes.loc[("uav1", 1)].label == "DoS"
    assert episodes.loc[("bs0", 1)].label == "Blackhole"
    assert episodes.loc[("uav3", 0)].label == "Benign" and episodes.loc[("uav3", 0)].attack_packets == 0
    assert sorted(episodes.index) == [("bs0", 0), ("bs0", 1), ("uav0", 1), ("uav0", 3), ("uav1", 1), ("uav1", 3),
                                      ("uav3", 0)]


def test_a_packet_seen_at_two_switches_counts_once(episodes):
    b = episodes.loc[("uav3", 0)]
    assert (b.packets, b.packets_out, b.packets_in, b.syn_out, b.synack_in, b.flows,
            b.flows_out) == (2, 1, 1, 1, 1, 1, 1)
    assert (b.bytes_out, b.bytes_in) == (54, 54)


def test_features_by_hand(episodes):
    v = episodes.loc[("uav0", 1)]
    assert (v.packets_out, v.packets_in, v.bytes_out, v.bytes_in) == (0, 5, 0, 3 * 54 + 2 * 154)
    assert v.packets_per_s == pytest.approx(5 / 5.0) and v.bytes_per_s == pytest.approx((3 * 54 + 2 * 154) / 5.0)
    assert v.active_s == pytest.approx(1.5)  # 6.0 .. 7.5
    assert (v.peers, v.peer_ports) == (2, 4)  # uav1 and bs0; ports 1000-1002 and 80
    assert (v.syn_in, v.syn_out, v.synack_in, v.rst_in, v.fin_in) == (3, 0, 0, 0, 0)
    assert (v.udp_share, v.icmp_share) == (0.0, 0.0)
    # flows: three one-SYN flood flows and bs0's 2-packet flow, all started by the peers
    assert (v.flows, v.flows_in, v.flows_out) == (4, 4, 0)
    assert v.fwd_packets_mean == pytest.approx((1 + 1 + 1 + 2) / 4) and v.fwd_packets_max == 2
    assert v.fwd_payload_bytes_max == 200 and v.flow_duration_us_max == pytest.approx(0.5e6)
    assert list(episodes.reset_index().columns[episodes.reset_index().columns.isin(episode_feature_columns())]) == list(
        episode_feature_columns())


def test_no_flow_starting_in_the_window_gives_nan_summaries():
    """A flow that starts at 4.9 s (window 0) and is answered at 5.1 s (window 1): its packets count in
    both windows' episodes, the flow only in the first; the second's flow summaries are NaN."""
    p = _table([dict(t=4.9, at="s-uav3", src="uav3", dst="bs0", sport=6000, dport=80, flags=SYN),
                dict(t=5.1, at="s-uav3", src="bs0", dst="uav3", sport=80, dport=6000, flags=SYN | ACK)])
    truth = PacketTruth(np.zeros(2, dtype=np.int8), np.full(2, -1, dtype=np.int8))
    fl = assemble(p, FlowConfig())
    df = host_window_frame(p, fl, flow_frame(p, fl), truth, make_plan(), T0).set_index(["host", "window"])
    first, second = df.loc[("uav3", 0)], df.loc[("uav3", 1)]
    assert (first.packets, first.flows, second.packets, second.flows) == (1, 1, 1, 0)
    assert first.flow_duration_us_mean == pytest.approx(0.2e6)
    summaries = [c for c in episode_feature_columns() if c.endswith(("_mean", "_max"))]
    assert second[summaries].isna().all() and first[summaries].notna().all()
    assert (second.label, second.packets_in, second.synack_in) == ("Benign", 1, 1)
    with pytest.raises(ValueError, match="5-tuple"):
        host_window_frame(p, assemble(p, FlowConfig(view="hostpair", min_packets=1)), flow_frame(p, fl), truth,
                          make_plan(), T0)


def test_route_columns_summarise_the_episodes_own_packets():
    """Six streams between bs0 and three UAVs over three windows; uav3 -> bs0 goes through uav1
    from 10.3 s: 1 of 6 pairs changed, so from the bin of the change its packets are on a lonely
    route; the episodes carry the route columns, finite, from the context's packet routes."""
    import pandas as pd

    from uavcas.flows.context import context_frames
    from uavcas.schema import EPISODE_ROUTE_FEATURES

    obs = []
    streams = [("uav3", "bs0"), ("bs0", "uav3"), ("uav0", "bs0"), ("bs0", "uav0"), ("uav1", "bs0"), ("bs0", "uav1")]
    for k in range(150):
        t = 0.1 * k
        for j, (src, dst) in enumerate(streams):
            path = [f"s-{src}", f"s-{dst}"]
            if (src, dst) == ("uav3", "bs0") and t >= 10.3:
                path = ["s-uav3", "s-uav1", "s-bs0"]
            obs += [dict(t=t + 0.01 * j + 0.001 * i, at=at, src=src, dst=dst, sport=6000 + j, dport=80, flags=ACK,
                         id=1000 * j + k) for i, at in enumerate(path)]  # one IP id per packet, at every switch
    p = _table(obs)
    truth = PacketTruth(np.zeros(len(p), dtype=np.int8), np.full(len(p), -1, dtype=np.int8))
    fl = assemble(p, FlowConfig())
    ctx, routes = context_frames(p, fl)
    ff = pd.concat([flow_frame(p, fl), ctx], axis=1)
    df = host_window_frame(p, fl, ff, truth, make_plan(), T0, routes=routes).set_index(["host", "window"])
    assert set(EPISODE_ROUTE_FEATURES) <= set(df.columns) and np.isfinite(df[list(EPISODE_ROUTE_FEATURES)]).all().all()
    # uav3's window 2 holds its 50 packets to bs0 (all lonely: from 10 s) and its 50 from bs0, its one peer
    v = df.loc[("uav3", 2)]
    assert (v.ctx_pkt_route_lonely_max, v.ctx_pkt_route_lonely_frac) == (pytest.approx(0.5), pytest.approx(0.5))
    assert v.ctx_pkt_path_len_shift == pytest.approx(0.47)  # one switch more on the 47 detoured of its 100
    assert df.loc[("uav3", 0),
                  "ctx_pkt_route_lonely_max"] == 0.0 and df.loc[("uav0", 2), "ctx_pkt_route_lonely_max"] == 0.0
    b = df.loc[("bs0", 2)]  # of bs0's three peers, uav3's traffic was half detoured
    assert (b.ctx_pkt_route_lonely_max, b.ctx_pkt_route_lonely_frac) == (pytest.approx(0.5), pytest.approx(50 / 300))
    # its path and delay shifts: a third of the victim pair's over bs0's three peers, whole per peer
    assert b.ctx_pkt_path_len_shift == pytest.approx(47 / 300)
    assert b.ctx_pkt_path_len_shift_peer_max == pytest.approx(0.47)
    assert b.ctx_pkt_delay_shift_peer_max_ms == pytest.approx(0.47, abs=1e-3)  # one hop of 1 ms on 47 of 100
    with pytest.raises(ValueError, match="routes"):
        host_window_frame(p, fl, ff, truth, make_plan(), T0)
