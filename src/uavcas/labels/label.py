"""Ground-truth labels of flows from the run's attack log.

Modes:
- `ours` (default): each family's own ground-truth rule (`AttackFamily.truth` in
  `uavcas.attacks.<family>`: packet-exact SYN floods, packet-exact replay injections, or flows
  touching a victim during the attack window); label_source names the rules that fired.
- `paper` (the authors' IP membership): a flow gets a family when its source or destination IP is
  one of the attack's attacker or victim IPs, over the whole run (no time gating);
  label_source "ip-membership".

Columns added: `label_<family>` (bool, multi-hot), `label` (schema.class_name of the set of
families: 'Benign', 'DoS', 'Blackhole+DoS', ...), `label_source` (the sources that fired, joined
by '+' in the order of SOURCES, or "none").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import pandas as pd

from uavcas.attacks import families, family
from uavcas.flows.assemble import Flows
from uavcas.flows.packets import PacketTable, address_to_words
from uavcas.schema import FAMILIES, class_name

from .attacklog import AttackLog, AttackWindow

LabelMode = Literal["ours", "paper"]
LABEL_MODES: tuple[str, ...] = ("ours", "paper")
PAPER_SOURCE = "ip-membership"
# Order of the parts of a label_source value (fixed: datasets compare across versions).
SOURCES: tuple[str, ...] = ("flood-packets", "replay-injections", "victim-window", PAPER_SOURCE)
assert {f.label_source for f in families()} <= set(SOURCES), "a family's label_source is missing from SOURCES"


@dataclass
class TruthContext:
    """What a family's ground-truth rule may look at: the run's packets, flows and attack log."""

    packets: PacketTable
    flows: Flows
    frame: pd.DataFrame
    log: AttackLog

    def __post_init__(self) -> None:
        self.n_flows = self.flows.n_flows
        self._packet_flow = self.flows.packet_flow(len(self.packets))

    def _addr_mask(self, hi: np.ndarray, lo: np.ndarray, ips) -> np.ndarray:
        mask = np.zeros(hi.shape[0], dtype=bool)
        for ip in ips:
            h, l = address_to_words(ip)
            mask |= (hi == np.uint64(h)) & (lo == np.uint64(l))
        return mask

    def packets_from(self, ips) -> np.ndarray:
        return self._addr_mask(self.packets["src_hi"], self.packets["src_lo"], ips)

    def packets_to(self, ips) -> np.ndarray:
        return self._addr_mask(self.packets["dst_hi"], self.packets["dst_lo"], ips)

    def flows_with(self, packet_mask: np.ndarray) -> np.ndarray:
        """Flow mask: the flows holding at least one of the masked packets."""
        f = self._packet_flow[packet_mask]
        hits = np.zeros(self.n_flows, dtype=bool)
        hits[np.unique(f[f >= 0])] = True
        return hits

    def victim_window(self, windows: list[AttackWindow]) -> np.ndarray:
        """Flows to or from a victim IP whose lifetime [first_ts, last_ts] overlaps [start, stop)."""
        src = self.frame["src_ip"].to_numpy(dtype=object)
        dst = self.frame["dst_ip"].to_numpy(dtype=object)
        first, last = self.frame["first_ts"].to_numpy(), self.frame["last_ts"].to_numpy()
        hits = np.zeros(len(self.frame), dtype=bool)
        for w in windows:
            victims = np.asarray(w.victim_ips, dtype=object)
            touches = np.isin(src, victims) | np.isin(dst, victims)
            hits |= touches & (first < w.stop_unix) & (last >= w.start_unix)
        return hits


def _family_flows_ours(p: PacketTable, fl: Flows, frame: pd.DataFrame, log: AttackLog) -> dict[str, np.ndarray]:
    ctx = TruthContext(p, fl, frame, log)
    return {f.name: f.truth(ctx, log.of_family(f.name)) for f in families()}


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
            src_names[c] = PAPER_SOURCE
        else:
            used = {family(f).label_source for f in fams}
            src_names[c] = "+".join(s for s in SOURCES if s in used)
    out["label"] = pd.Series(code).map(names).to_numpy(dtype=object)
    out["label_source"] = pd.Series(code).map(src_names).to_numpy(dtype=object)
    return out
