"""Packets that answer given packets, matched packet to packet, for the families' provoked rules
(`AttackFamily.provoked`).

An answer is tied to the packet it answers by header fields only the two share: the 5-tuple
(the same or reversed) together with a sequence or acknowledgement number computed from the
answered packet, or, for an ICMP error, the packet it quotes (`q_*` columns of the packet table).
Hosts and times alone never make an answer (labelling by host and time is the defect of the
labels we re-implement); time only bounds the search: an answer comes after the packet it
answers and within `ANSWER_WITHIN_S` of it, whatever the attack window (a victim still answers
after the attacker stopped).

All of it is vectorised: one pandas merge of candidate rows with the answered rows on the key.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from uavcas.flows.packets import PacketTable, payload_and_header

TCP_FIN, TCP_SYN, TCP_RST, TCP_ACK = 0x01, 0x02, 0x04, 0x10
SEQ_MOD = 1 << 32  # TCP sequence arithmetic
# Linux retransmits an unanswered SYN-ACK tcp_synack_retries times (default 5), 1, 2, 4, 8 and
# 16 s apart: the last one leaves 31 s after the first, and the RST answering it follows at
# once. The first SYN-ACK itself can wait for a flood's queues (well under a second on the
# emulated links). 40 s covers all of them; the 5-tuple and sequence numbers, not this bound,
# tell an answer from an unrelated packet.
ANSWER_WITHIN_S = 40.0

_ENDS = ("src_hi", "src_lo", "dst_hi", "dst_lo", "sport", "dport")
_REVERSED = ("dst_hi", "dst_lo", "src_hi", "src_lo", "dport", "sport")


def tcp_flags_are(p: "PacketTable", flags: int, mask: int) -> np.ndarray:
    """TCP rows whose flags under `mask` are exactly `flags`."""
    return (p["proto"] == 6) & ((p["tcp_flags"] & mask) == flags)


def payload_len(p: "PacketTable") -> np.ndarray:
    """TCP/UDP payload bytes of every row (as `flows.packets.payload_and_header`), int64."""
    return payload_and_header(p["proto"], p["ip_len"], p["ip_hdr_len"], p["l4_hdr_len"])[0]


def _matched(cand: pd.DataFrame, trig: pd.DataFrame, on: list[str], within_s: float, n: int) -> np.ndarray:
    """Mask of the `row`s of `cand` that meet a `trig` row on `on`, 0 <= t - t_trig <= within_s."""
    out = np.zeros(n, dtype=bool)
    if cand.empty or trig.empty:
        return out
    m = cand.merge(trig, on=on, how="inner", suffixes=("", "_trig"))
    dt = m["t"].to_numpy() - m["t_trig"].to_numpy()
    out[m["row"].to_numpy()[(dt >= 0.0) & (dt <= within_s)]] = True
    return out


def answers(p: "PacketTable", answered: np.ndarray, cand: np.ndarray, reverse: bool, field: str,
            value: np.ndarray, within_s: float = ANSWER_WITHIN_S) -> np.ndarray:
    """Rows of `cand` on the 5-tuple of an `answered` row (reversed when `reverse`: the answer
    goes back to the sender) whose TCP `field` ("tcp_seq" or "tcp_ack") equals `value` (one per
    answered row, taken mod 2^32), at most `within_s` after it."""
    n = len(p)
    a, c = np.flatnonzero(answered), np.flatnonzero(cand & (p["proto"] == 6))
    if a.shape[0] == 0 or c.shape[0] == 0:
        return np.zeros(n, dtype=bool)
    ends = _REVERSED if reverse else _ENDS
    trig = pd.DataFrame({k: p[src][a] for k, src in zip(_ENDS, ends)})
    trig["proto"] = 6
    trig["num"] = np.asarray(value, dtype=np.int64) % SEQ_MOD
    trig["t"] = p["ts_s"][a]
    cands = pd.DataFrame({k: p[k][c] for k in _ENDS})
    cands["proto"] = 6
    cands["num"] = p[field][c].astype(np.int64)
    cands["t"], cands["row"] = p["ts_s"][c], c
    return _matched(cands, trig, [*_ENDS, "proto", "num"], within_s, n)


def udp_answers(p: "PacketTable", answered: np.ndarray, cand: np.ndarray,
                within_s: float = ANSWER_WITHIN_S) -> np.ndarray:
    """UDP rows of `cand` on the reversed 5-tuple of an `answered` UDP row (from its destination
    address and port back to its source address and port), at most `within_s` after it. UDP has
    no sequence number: the 5-tuple is the whole key, so it ties an answer only where nothing else
    travels on that reversed 5-tuple (an attacker's own ephemeral port, `attacks.mavlink_inject`)."""
    n = len(p)
    a = np.flatnonzero(answered & (p["proto"] == 17))
    c = np.flatnonzero(cand & (p["proto"] == 17))
    if a.shape[0] == 0 or c.shape[0] == 0:
        return np.zeros(n, dtype=bool)
    trig = pd.DataFrame({k: p[src][a] for k, src in zip(_ENDS, _REVERSED)})
    trig["t"] = p["ts_s"][a]
    cands = pd.DataFrame({k: p[k][c] for k in _ENDS})
    cands["t"], cands["row"] = p["ts_s"][c], c
    return _matched(cands, trig, list(_ENDS), within_s, n)


def icmp_errors_quoting(p: "PacketTable", answered: np.ndarray, exact: bool = False,
                        within_s: float = ANSWER_WITHIN_S) -> np.ndarray:
    """ICMP errors that quote an `answered` row: the quoted protocol, addresses (low words),
    ports and TCP seq are the answered packet's, and the error goes to its source (an error is
    sent to the quoted packet's sender). `exact` also asks for the quoted IP id and TTL: a
    replayed copy differs from its original only there (and in the seq, which a replay may keep).
    The emulation forwards at layer 2, so a quote keeps the TTL the copy was sent with."""
    n = len(p)
    a = np.flatnonzero(answered)
    c = np.flatnonzero(p["q_proto"] > 0)
    if a.shape[0] == 0 or c.shape[0] == 0:
        return np.zeros(n, dtype=bool)
    a_tcp = p["proto"][a] == 6
    trig = pd.DataFrame({
        "to_hi": p["src_hi"][a], "to_lo": p["src_lo"][a], "q_proto": p["proto"][a].astype(np.int64),
        "q_src_lo": p["src_lo"][a], "q_dst_lo": p["dst_lo"][a], "q_sport": p["sport"][a].astype(np.int64),
        "q_dport": p["dport"][a].astype(np.int64),
        "q_tcp_seq": np.where(a_tcp, p["tcp_seq"][a].astype(np.int64), 0), "t": p["ts_s"][a],
    })  # fmt: skip
    cands = pd.DataFrame({
        "to_hi": p["dst_hi"][c], "to_lo": p["dst_lo"][c], "q_proto": p["q_proto"][c].astype(np.int64),
        "q_src_lo": p["q_src_lo"][c], "q_dst_lo": p["q_dst_lo"][c], "q_sport": p["q_sport"][c].astype(np.int64),
        "q_dport": p["q_dport"][c].astype(np.int64), "q_tcp_seq": p["q_tcp_seq"][c].astype(np.int64),
        "t": p["ts_s"][c], "row": c,
    })  # fmt: skip
    on = ["to_hi", "to_lo", "q_proto", "q_src_lo", "q_dst_lo", "q_sport", "q_dport", "q_tcp_seq"]
    if exact:
        trig["q_ip_id"], trig["q_ttl"] = p["ip_id"][a].astype(np.int64), p["ttl"][a].astype(np.int64)
        cands["q_ip_id"], cands["q_ttl"] = p["q_ip_id"][c].astype(np.int64), p["q_ttl"][c].astype(np.int64)
        on += ["q_ip_id", "q_ttl"]
    return _matched(cands, trig, on, within_s, n)
