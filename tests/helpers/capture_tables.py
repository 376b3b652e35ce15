"""Packet tables built by hand (`uavcas.flows.packets.PacketTable`): packets seen at named
switches, for the context and route tests of `uavcas.flows`."""

from __future__ import annotations

import numpy as np

from uavcas.flows.packets import COLUMNS, QUOTE_COLUMNS, PacketTable, address_to_words, empty_columns

T0 = 1_600_000_000.0  # a multiple of the 5 s window: window k is [T0 + 5k, T0 + 5k + 5)
IPS = {"a": "10.0.0.1", "b": "10.0.0.2", "r": "10.0.0.3", "x": "10.0.0.4", "bs0": "10.0.0.5", "bs1": "10.0.0.6"}
POINTS = ("s-a", "s-b", "s-r", "s-x", "s-bs0", "s-bs1")  # s-bs<k>: a base station's switch (docs/formats.md)
HOP_S = 0.001
_DTYPES = {"ts_ns": np.int64, "ip_len": np.uint32, "frame_len": np.uint32, "cap_len": np.uint32, "ip_version": np.uint8,
           "src_hi": np.uint64, "src_lo": np.uint64, "dst_hi": np.uint64, "dst_lo": np.uint64, "sport": np.uint16,
           "dport": np.uint16, "proto": np.uint8, "tcp_flags": np.uint16, "ttl": np.uint8, "ip_id": np.uint32,
           "tcp_seq": np.uint32, "tcp_ack": np.uint32, "ip_hdr_len": np.uint16, "l4_hdr_len": np.uint16,
           "frame_index": np.int64,
           "point": np.int16, **{c: empty_columns()[c].dtype for c in QUOTE_COLUMNS},
           "mav_msgid": np.int32}
QUOTE_ZERO = {**{c: 0 for c in QUOTE_COLUMNS}, "mav_msgid": -1}  # TCP only: no ICMP error quotes a packet


def table(obs: list[dict], ips: dict[str, str] = IPS) -> PacketTable:
    """obs: t (s from T0), at (switch), src, dst (hosts), payload bytes and TCP header fields (or
    proto 17: a UDP datagram, no flags or seq)."""
    cols = {c: [] for c in COLUMNS}
    for k, o in enumerate(obs):
        shi, slo = address_to_words(ips[o["src"]])
        dhi, dlo = address_to_words(ips[o["dst"]])
        udp = o.get("proto", 6) == 17
        length = (42 if udp else 54) + o.get("payload", 0)
        vals = {"ts_ns": round(T0) * 10**9 + round(o["t"] * 1e9), "frame_len": length, "cap_len": length,
                "ip_version": 4,
                "ip_len": length - 14, "src_hi": shi, "src_lo": slo, "dst_hi": dhi, "dst_lo": dlo,
                "sport": o["sport"], "dport": o["dport"], "proto": o.get("proto", 6), "tcp_flags": o.get("flags", 0),
                "ttl": o.get("ttl", 64), "ip_id": o["id"], "tcp_seq": o.get("seq", 0), "tcp_ack": o.get("ack", 0),
                "ip_hdr_len": 20, "l4_hdr_len": 8 if udp else 20, "frame_index": k,
                "point": POINTS.index("s-" + o["at"]), **QUOTE_ZERO}
        for c in COLUMNS:
            cols[c].append(vals[c])
    return PacketTable({c: np.array(v, dtype=_DTYPES[c]) for c, v in cols.items()}, POINTS)


def send(t, path, src, dst, **hdr) -> list[dict]:
    """One packet seen at each switch of `path` in turn, HOP_S apart."""
    return [{"t": t + k * HOP_S, "at": n, "src": src, "dst": dst, **hdr} for k, n in enumerate(path)]
