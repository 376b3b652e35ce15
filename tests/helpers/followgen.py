"""A four-switch plan and hand-built packet tables, for the follower's and the audit's tests.

Topology (window 0): uav0 - uav1 - bs0, uav0 - uav2, uav2 - bs0; routes send uav0 <-> bs0
through uav1. Window 1 drops uav0 - uav1, so the same traffic goes through uav2.
"""

from __future__ import annotations

import numpy as np

from helpers.pcapgen import T0
from uavcas.flows.follow import Timeline
from uavcas.flows.packets import COLUMNS, QUOTE_COLUMNS, PacketTable, address_to_words, empty_columns
from uavcas.network.forwarding import compute
from uavcas.twin.model import Link, Node, Plan, Route, Window

NAMES = ["uav0", "uav1", "uav2", "bs0"]
IPS = {n: f"10.9.0.{i + 1}" for i, n in enumerate(NAMES)}
POINTS = tuple(f"s-{n}" for n in NAMES)
D_MS = 5.0


def link(a, b, delay_ms=D_MS):
    return Link(a=a, b=b, kind="air", distance_m=50.0, pathloss_db=70.0, snr_db=25.0, mcs=4, rate_mbps=24.0,
                delay_ms=delay_ms, loss=0.0)


def plan() -> Plan:
    nodes = [Node(name=n, kind="bs" if n.startswith("bs") else "uav", index=i, ip=IPS[n],
                  mac=f"02:00:00:00:00:{i:02x}") for i, n in enumerate(NAMES)]
    w0 = Window(index=0, t_s=0.0, duration_s=5.0, positions={},
                links=[link("uav0", "uav1"), link("uav1", "bs0"), link("uav0", "uav2"), link("uav2", "bs0")],
                routes=[Route(src="uav0", dst="bs0", hops=["uav0", "uav1", "bs0"])])
    w1 = Window(index=1, t_s=5.0, duration_s=5.0, positions={},
                links=[link("uav0", "uav2"), link("uav2", "bs0"), link("uav1", "bs0")], routes=[])
    return Plan(config="test", seed=0, window_s=5.0, profile="test", area_m=(100.0, 100.0, 10.0, 50.0),
                nodes=nodes, windows=[w0, w1], attacks=[])


PLAN = plan()
TL = Timeline.from_plan(PLAN, T0)


QUOTE_ZERO = {**{c: 0 for c in QUOTE_COLUMNS}, "mav_msgid": -1}  # no ICMP error quotes a packet here


def table(rows: list[dict]) -> PacketTable:
    """rows: t (s from T0), at (node), src, dst (nodes), and optional header fields."""
    cols = {c: [] for c in COLUMNS}
    for k, r in enumerate(rows):
        shi, slo = address_to_words(IPS.get(r["src"], r["src"]))
        dhi, dlo = address_to_words(IPS.get(r["dst"], r["dst"]))
        vals = {"ts_ns": round((T0 + r["t"]) * 1e9), "frame_len": r.get("len", 142), "cap_len": r.get("len", 142),
                "ip_version": 4, "ip_len": r.get("len", 142) - 14,
                "src_hi": shi, "src_lo": slo, "dst_hi": dhi, "dst_lo": dlo, "sport": r.get("sport", 5000),
                "dport": r.get("dport", 6000), "proto": r.get("proto", 17), "tcp_flags": r.get("flags", 0),
                "ttl": r.get("ttl", 64), "ip_id": r.get("id", 0), "tcp_seq": r.get("seq", 0),
                "tcp_ack": r.get("ack", 0), "ip_hdr_len": 20,
                "l4_hdr_len": 8, "frame_index": k, "point": NAMES.index(r["at"]), **QUOTE_ZERO}
        for c in COLUMNS:
            cols[c].append(vals[c])
    dtypes = {"ts_ns": np.int64, "ip_len": np.uint32, "frame_len": np.uint32, "cap_len": np.uint32,
              "ip_version": np.uint8,
              "src_hi": np.uint64, "src_lo": np.uint64, "dst_hi": np.uint64, "dst_lo": np.uint64,
              "sport": np.uint16, "dport": np.uint16, "proto": np.uint8, "tcp_flags": np.uint16, "ttl": np.uint8,
              "ip_id": np.uint32, "tcp_seq": np.uint32, "tcp_ack": np.uint32, "ip_hdr_len": np.uint16,
              "l4_hdr_len": np.uint16,
              "frame_index": np.int64, "point": np.int16, **{c: empty_columns()[c].dtype for c in QUOTE_COLUMNS},
              "mav_msgid": np.int32}
    return PacketTable({c: np.array(v, dtype=dtypes[c]) for c, v in cols.items()}, POINTS)


def send(t, path, d_s=D_MS / 1000, **hdr):
    """Observations of one packet along `path` (nodes), one planned delay per hop."""
    return [{"t": t + k * d_s, "at": n, "src": path[0], "dst": path[-1], **hdr} for k, n in enumerate(path)]



def next_hops(w: int):
    win = PLAN.windows[w]
    return compute(NAMES, [(lk.a, lk.b) for lk in win.links], [r.hops for r in win.routes]).next_hop


TL_NH = [next_hops(0), next_hops(1)]
