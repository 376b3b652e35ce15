"""Hand-built packet tables and TruthContexts for the per-packet truth rules (no pcap, no root).

The plan is synth_run's (uav0 - uav1, uav0/uav2/uav3 - bs0 linked in every 5 s window). A packet
is given once, with its header fields; it is observed at its sender's switch and, HOP_S later,
at its receiver's (`at` names other switches, e.g. only the sender's for a packet dropped or lost
there). ICMP errors name the packet they quote (`quote`: a packet dict).
"""

from __future__ import annotations

import numpy as np

from helpers.synth_run import HOP_S, IPS, T0, make_plan
from uavcas.flows.follow import Timeline, follow
from uavcas.flows.packets import COLUMNS, PacketTable, address_to_words, empty_columns
from uavcas.labels.attacklog import AttackLog, AttackWindow, Injection
from uavcas.labels.effects import TruthContext

FIN, SYN, RST, PSH, ACK = 0x01, 0x02, 0x04, 0x08, 0x10
PLAN = make_plan()
NODES = [n.name for n in PLAN.nodes]
POINTS = tuple(f"s-{n}" for n in NODES)


def pkt(t, src, dst, sport=0, dport=0, flags=0, seq=0, ack=0, ip_id=0, ttl=64, payload=0, proto=6, at=None,
        quote=None, mav_msgid=-1) -> dict:
    return dict(t=t, src=src, dst=dst, sport=sport, dport=dport, flags=flags, seq=seq, ack=ack, ip_id=ip_id, ttl=ttl,
                payload=payload, proto=proto, at=at or [src, dst], quote=quote, mav_msgid=mav_msgid)


def icmp_error(t, src, dst, quote: dict, ip_id=0) -> dict:
    """An ICMP destination unreachable (type 3) from `src` to `dst` quoting the packet `quote`."""
    return pkt(t, src, dst, proto=1, ip_id=ip_id, payload=0, quote=quote)


def table(packets: list[dict]) -> PacketTable:
    cols: dict[str, list] = {c: [] for c in COLUMNS}
    k = 0
    for p in packets:
        shi, slo = address_to_words(IPS[p["src"]])
        dhi, dlo = address_to_words(IPS[p["dst"]])
        l4 = 20 if p["proto"] == 6 else 8
        q = p["quote"]
        ip_len = 20 + l4 + (p["payload"] if q is None else 20 + 8)
        quoted = {"q_proto": 0, "q_src_lo": 0, "q_dst_lo": 0, "q_sport": 0, "q_dport": 0, "q_ip_id": 0, "q_ttl": 0,
                  "q_tcp_seq": 0}
        if q is not None:
            quoted = {"q_proto": q["proto"], "q_src_lo": address_to_words(IPS[q["src"]])[1],
                      "q_dst_lo": address_to_words(IPS[q["dst"]])[1], "q_sport": q["sport"], "q_dport": q["dport"],
                      "q_ip_id": q["ip_id"], "q_ttl": q["ttl"], "q_tcp_seq": q["seq"] if q["proto"] == 6 else 0}
        for hop, node in enumerate(p["at"]):
            vals = {"ts_ns": round((T0 + p["t"] + hop * HOP_S) * 1e9), "frame_len": ip_len + 14, "cap_len": ip_len + 14,
                    "ip_version": 4, "src_hi": shi, "src_lo": slo, "dst_hi": dhi, "dst_lo": dlo,
                    "sport": p["sport"], "dport": p["dport"], "proto": p["proto"], "tcp_flags": p["flags"],
                    "ttl": p["ttl"], "ip_id": p["ip_id"], "tcp_seq": p["seq"], "tcp_ack": p["ack"], "ip_len": ip_len,
                    "ip_hdr_len": 20, "l4_hdr_len": l4, "frame_index": k, "point": POINTS.index(f"s-{node}"),
                    "mav_msgid": p["mav_msgid"], **quoted}
            k += 1
            for c in COLUMNS:
                cols[c].append(vals[c])
    dtypes = {c: a.dtype for c, a in empty_columns().items()}
    return PacketTable({c: np.array(v, dtype=dtypes[c]) for c, v in cols.items()}, POINTS)


def window(family: str, attacker: str, victim: str, start_s: float, stop_s: float,
           aid: str | None = None) -> AttackWindow:
    return AttackWindow(attack_id=aid or f"{family}-0", family=family, attacker_ips=(IPS[attacker],),
                        victim_ips=(IPS[victim],), start_unix=T0 + start_s, stop_unix=T0 + stop_s)


def injection(p: dict, aid: str = "replay-0") -> Injection:
    """The inject record of the injected packet `p` (logged as it leaves the replayer)."""
    return Injection(attack_id=aid, t_unix=T0 + p["t"], src_ip=IPS[p["src"]], dst_ip=IPS[p["dst"]], protocol=p["proto"],
                     ip_id=p["ip_id"], ttl=p["ttl"], seq=p["seq"] if p["proto"] == 6 else None,
                     src_port=p["sport"] if p["proto"] in (6, 17) else None,
                     dst_port=p["dport"] if p["proto"] in (6, 17) else None)


def context(packets: list[dict], windows: list[AttackWindow], injections: list[Injection] = ()) -> TruthContext:
    t = table(packets)
    return TruthContext(t, AttackLog(windows=tuple(windows), injections=tuple(injections)),
                        follow(t, Timeline.from_plan(PLAN, T0)), PLAN, T0)


def rows_of(ctx: TruthContext, p: dict) -> np.ndarray:
    """Mask of the observations of the packet `p` (its header fields and time)."""
    t = ctx.packets
    shi, slo = address_to_words(IPS[p["src"]])
    hit = (t["src_lo"] == np.uint64(slo)) & (t["dst_lo"] == np.uint64(address_to_words(IPS[p["dst"]])[1]))
    hit &= (t["sport"] == p["sport"]) & (t["dport"] == p["dport"]) & (t["proto"] == p["proto"])
    hit &= ((t["tcp_flags"] == p["flags"]) & (t["tcp_seq"] == p["seq"]) & (t["ip_id"] == p["ip_id"])
            & (t["ttl"] == p["ttl"]))
    hit &= np.abs(t["ts_s"] - (T0 + p["t"])) < 0.5 * 1e-3 + len(p["at"]) * HOP_S
    assert hit.sum() == len(p["at"]), p
    return hit
