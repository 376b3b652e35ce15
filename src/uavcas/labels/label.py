"""Ground-truth labels of flows from the run's attack log.

Modes:
- `ours` (default), how each family is decided:
  * dos / ddos  -> "flood-packets": a flow is labelled when it carries at least one packet of the
    flood, i.e. a TCP packet with SYN set and ACK clear, from one of the attack's attacker IPs to
    one of its victim IPs, captured inside [start, stop) of that attack (packet-exact: the same
    host pair outside the window, or answering SYN-ACKs alone, do not make a flood flow).
  * replay      -> "replay-injections": a flow carries a packet matching an `inject` record on
    (src_ip, dst_ip, ip_id, ttl, and seq for TCP) captured within REPLAY_MATCH_TOLERANCE_S of the
    record's t_unix (packet-exact).
  * blackhole / wormhole -> "victim-window": a flow to or from a victim IP whose lifetime
    [first_ts, last_ts] overlaps the attack window [start, stop).
- `paper` (the authors' IP membership): a flow gets a family when its source or destination IP is
  one of the attack's attacker or victim IPs, over the whole run (no time gating);
  label_source "ip-membership".

Columns added: `label_<family>` (bool, multi-hot), `label` (schema.class_name of the set of
families: 'Benign', 'DoS', 'Blackhole+DoS', ...), `label_source` (the sources that fired, joined
by '+' in the order of SOURCES, or "none").
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pandas as pd

from uavcas.dataset.schema import FAMILIES, class_name
from uavcas.flows.assemble import Flows
from uavcas.flows.packets import PacketTable, address_to_words

from .attacklog import AttackLog

LabelMode = Literal["ours", "paper"]
LABEL_MODES: tuple[str, ...] = ("ours", "paper")
REPLAY_MATCH_TOLERANCE_S = 1.0
SOURCES: tuple[str, ...] = ("flood-packets", "replay-injections", "victim-window", "ip-membership")
FAMILY_SOURCE = {
    "dos": "flood-packets",
    "ddos": "flood-packets",
    "replay": "replay-injections",
    "blackhole": "victim-window",
    "wormhole": "victim-window",
}
TCP_SYN, TCP_ACK = 0x02, 0x10


def _addr_mask(hi: np.ndarray, lo: np.ndarray, ips) -> np.ndarray:
    mask = np.zeros(hi.shape[0], dtype=bool)
    for ip in ips:
        h, l = address_to_words(ip)
        mask |= (hi == np.uint64(h)) & (lo == np.uint64(l))
    return mask


def _flows_of(packet_flow: np.ndarray, mask: np.ndarray) -> np.ndarray:
    f = packet_flow[mask]
    return np.unique(f[f >= 0])


def _replay_packets(p: PacketTable, log: AttackLog) -> np.ndarray:
    """Mask of packets that match an inject record (see module rules)."""
    mask = np.zeros(len(p), dtype=bool)
    if not log.injections or len(p) == 0:
        return mask
    inj = pd.DataFrame(
        {
            "src": [address_to_words(i.src_ip)[1] for i in log.injections],
            "dst": [address_to_words(i.dst_ip)[1] for i in log.injections],
            "src_hi": [address_to_words(i.src_ip)[0] for i in log.injections],
            "dst_hi": [address_to_words(i.dst_ip)[0] for i in log.injections],
            "ip_id": [i.ip_id for i in log.injections],
            "ttl": [i.ttl for i in log.injections],
            "seqk": [-1 if (i.seq is None or i.protocol != 6) else i.seq for i in log.injections],
            "t_inj": [i.t_unix for i in log.injections],
        }
    ).astype({"src": np.uint64, "dst": np.uint64, "src_hi": np.uint64, "dst_hi": np.uint64, "ip_id": np.int64, "ttl": np.int64, "seqk": np.int64})
    cand = np.flatnonzero(np.isin(p["src_lo"], inj["src"].to_numpy()))
    pk = pd.DataFrame(
        {
            "row": cand,
            "src": p["src_lo"][cand],
            "dst": p["dst_lo"][cand],
            "src_hi": p["src_hi"][cand],
            "dst_hi": p["dst_hi"][cand],
            "ip_id": p["ip_id"][cand].astype(np.int64),
            "ttl": p["ttl"][cand].astype(np.int64),
            "seqk": np.where(p["proto"][cand] == 6, p["tcp_seq"][cand].astype(np.int64), -1),
            "ts": p["ts_s"][cand],
        }
    )
    m = pk.merge(inj, on=["src", "dst", "src_hi", "dst_hi", "ip_id", "ttl", "seqk"], how="inner")
    hit = m.loc[(m["ts"] - m["t_inj"]).abs() <= REPLAY_MATCH_TOLERANCE_S, "row"].to_numpy()
    mask[hit] = True
    return mask


def _family_flows_ours(p: PacketTable, fl: Flows, frame: pd.DataFrame, log: AttackLog) -> dict[str, np.ndarray]:
    n = fl.n_flows
    pflow = fl.packet_flow(len(p))
    hits = {f: np.zeros(n, dtype=bool) for f in FAMILIES}
    syn_only = (p["proto"] == 6) & ((p["tcp_flags"] & (TCP_SYN | TCP_ACK)) == TCP_SYN)
    for w in log.of_family("dos", "ddos"):
        mask = (
            syn_only
            & (p["ts_s"] >= w.start_unix)
            & (p["ts_s"] < w.stop_unix)
            & _addr_mask(p["src_hi"], p["src_lo"], w.attacker_ips)
            & _addr_mask(p["dst_hi"], p["dst_lo"], w.victim_ips)
        )
        hits[w.family][_flows_of(pflow, mask)] = True
    if log.injections:
        hits["replay"][_flows_of(pflow, _replay_packets(p, log))] = True
    src = frame["src_ip"].to_numpy(dtype=object)
    dst = frame["dst_ip"].to_numpy(dtype=object)
    first, last = frame["first_ts"].to_numpy(), frame["last_ts"].to_numpy()
    for w in log.of_family("blackhole", "wormhole"):
        victims = np.asarray(w.victim_ips, dtype=object)
        touches = np.isin(src, victims) | np.isin(dst, victims)
        hits[w.family] |= touches & (first < w.stop_unix) & (last >= w.start_unix)
    return hits


def _family_flows_paper(frame: pd.DataFrame, log: AttackLog) -> dict[str, np.ndarray]:
    n = len(frame)
    hits = {f: np.zeros(n, dtype=bool) for f in FAMILIES}
    src = frame["src_ip"].to_numpy(dtype=object)
    dst = frame["dst_ip"].to_numpy(dtype=object)
    for w in log.windows:
        ips = np.asarray(w.attacker_ips + w.victim_ips, dtype=object)
        hits[w.family] |= np.isin(src, ips) | np.isin(dst, ips)
    return hits


def label_flows(
    p: PacketTable, fl: Flows, frame: pd.DataFrame, log: AttackLog, mode: LabelMode = "ours"
) -> pd.DataFrame:
    """Return `frame` with the label columns added (see module docstring)."""
    if mode not in LABEL_MODES:
        raise ValueError(f"unknown label mode {mode!r}; known: {', '.join(LABEL_MODES)}")
    hits = _family_flows_ours(p, fl, frame, log) if mode == "ours" else _family_flows_paper(frame, log)
    out = frame.copy()
    code = np.zeros(len(frame), dtype=np.int64)
    for k, fam in enumerate(FAMILIES):
        out[f"label_{fam}"] = hits[fam]
        code |= hits[fam].astype(np.int64) << k
    names, src_names = {}, {}
    for c in np.unique(code).tolist():
        fams = [f for k, f in enumerate(FAMILIES) if c >> k & 1]
        names[c] = class_name(fams)
        if not fams:
            src_names[c] = "none"
        elif mode == "paper":
            src_names[c] = "ip-membership"
        else:
            used = {FAMILY_SOURCE[f] for f in fams}
            src_names[c] = "+".join(s for s in SOURCES if s in used)
    out["label"] = pd.Series(code).map(names).to_numpy(dtype=object)
    out["label_source"] = pd.Series(code).map(src_names).to_numpy(dtype=object)
    return out
