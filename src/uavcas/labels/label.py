"""Ground-truth labels of flows from the effects of their packets (`labels.effects`).

Columns added to the flow frame, whatever the mode:
- `seq_effect`: one effect per packet of the flow, aligned with the other `seq_*` columns;
- `attack_packets`: packets with an attack effect (not benign, not channel_loss: made, moved,
  dropped or provoked), `attack_fraction` = attack_packets / packets exactly,
  `provoked_packets`: those of them with the effect `provoked`, and `attack_packets_<family>`
  per family (a provoked packet counts for the family that provoked it).

Modes:
- `ours` (default): a flow carries family F when at least one of its packets has F's made, moved,
  dropped or provoked effect (each family's rules: `AttackFamily.effects` and
  `AttackFamily.provoked` in `uavcas.attacks.<family>`); a victim's flow none of whose packets
  was affected or provoked is Benign. With `min_attack_fraction` X > 0
  a flow with attack packets but attack_fraction < X is neither a clean attack flow nor a benign
  one: it is left out of the dataset (and counted). label_source names the rules that fired.
- `paper` (the authors' IP membership): a flow gets a family when its source or destination IP is
  one of the attack's attacker or victim IPs, over the whole run (no time gating);
  label_source "ip-membership". `min_attack_fraction` does not apply.

Then `label_<family>` (bool, multi-hot), `label` (schema.class_name of the set of families:
'Benign', 'DoS', 'Blackhole+DoS', ...) and `label_source` (the sources that fired, joined by '+'
in the order of SOURCES, or "none").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import pyarrow as pa

from uavcas.attacks import families, family
from uavcas.flows.assemble import Flows
from uavcas.schema import FAMILIES, class_name
from uavcas.vocabulary import (
    ATTACK_PACKET_COLUMNS,
    EFFECT_PRECEDENCE,
    EFFECTS,
    LABEL_MODES,
    LABEL_SOURCES,
    LabelMode,
)

from .attacklog import AttackLog
from .effects import PacketTruth

PAPER_SOURCE = "ip-membership"
# Order of the parts of a label_source value (fixed: datasets compare across versions): the families'
# sources in the order of the vocabulary's rows (append-only), then PAPER_SOURCE (never combined with
# another), so stored values keep their form.
SOURCES: tuple[str, ...] = LABEL_SOURCES + (PAPER_SOURCE,)


@dataclass(frozen=True)
class Labelled:
    frame: pd.DataFrame
    impure_dropped: int  # flows left out for attack_fraction below min_attack_fraction


def rule_text(mode: str, min_attack_fraction: float = 0.0) -> str:
    """The label rule in words, for the dataset card."""
    if mode == "paper":
        return ("paper: a flow carries family F when its source or destination IP is one of the "
                "attacker or victim IPs of an attack of F, over the whole run")
    parts = [f"{f.name}: {f.truth_rule}; provoked: {f.provoked_rule}" for f in families()]
    pure = (f"; flows with 0 < attack_fraction < {min_attack_fraction:g} are left out"
            if min_attack_fraction > 0 else "")
    return ("ours: a flow carries family F when at least one of its packets has F's made, moved, dropped or "
            f"provoked effect{pure}. Effects per packet (precedence {' > '.join(EFFECT_PRECEDENCE)}): "
            + " | ".join(parts))


def rule_summary(rules: list[str]) -> tuple[list[str], list[str]]:
    """The card's rule texts (`rule_text`, `dataset.json: label_rules`) for people: each text's
    first sentence (its policy), and the parts of every text: its policy with the effect
    precedence, then each family's rule (a text joins them with " | "), for the report and the
    published card."""
    headlines = [rule.split(". ", 1)[0].rstrip(".") + "." for rule in rules]
    parts = []
    for rule in rules:
        first, *rest = (p.strip() for p in rule.split(" | "))
        # the first part is the policy, the effect precedence, then the first family's rule
        head, sep, fam = first.partition("): ") if "(precedence " in first else (first, "", "")
        parts += [head + ")", fam] if sep else [head]
        parts += rest
    return headlines, parts


def truth_columns(fl: Flows, truth: PacketTruth) -> pd.DataFrame:
    """seq_effect, attack_packets, attack_fraction, provoked_packets and attack_packets_<family>,
    one row per flow."""
    n = fl.n_flows
    rows = fl.order
    fam = truth.family[rows].astype(np.int64)
    g = fl.flow
    counts = np.bincount(g, minlength=n).astype(np.int64)
    attack = np.bincount(g, weights=(fam >= 0).astype(np.float64), minlength=n).astype(np.int64)
    provoked = (truth.effect[rows] == EFFECTS.index("provoked")).astype(np.float64)
    out: dict[str, object] = {
        "attack_packets": attack,
        "attack_fraction": np.where(counts > 0, attack / np.maximum(counts, 1), 0.0),
        "provoked_packets": np.bincount(g, weights=provoked, minlength=n).astype(np.int64),
    }
    for k, f in enumerate(FAMILIES):
        out[ATTACK_PACKET_COLUMNS[k]] = np.bincount(g, weights=(fam == k).astype(np.float64),
                                                    minlength=n).astype(np.int64)
    names = pa.DictionaryArray.from_arrays(pa.array(truth.effect[rows].astype(np.int32)), pa.array(EFFECTS))
    seq = pa.ListArray.from_arrays(pa.array(fl.starts.astype(np.int32)), names.cast(pa.string()))
    df = pd.DataFrame(out)
    df.insert(0, "seq_effect", pd.arrays.ArrowExtensionArray(seq))
    return df


def constructed_truth(frame: pd.DataFrame) -> pd.DataFrame:
    """The truth columns of generated flows whose labels hold by construction (`label_<family>`
    set): every packet of an attack flow has the effect of its strongest family
    (vocabulary.EFFECT_PRECEDENCE), every packet of another flow is benign; none is provoked."""
    n = len(frame)
    packets = frame["packets"].to_numpy(dtype=np.int64)
    code = np.zeros(n, dtype=np.int64)  # index into EFFECTS
    fam = np.full(n, -1, dtype=np.int64)
    for k, f in sorted(enumerate(FAMILIES), key=lambda kf: EFFECT_PRECEDENCE.index(family(kf[1]).effect), reverse=True):
        hit = frame[f"label_{f}"].to_numpy(dtype=bool)
        code[hit], fam[hit] = EFFECTS.index(family(f).effect), k
    attack = np.where(fam >= 0, packets, 0)
    out = {"attack_packets": attack, "attack_fraction": np.where(fam >= 0, 1.0, 0.0),
           "provoked_packets": np.zeros(n, dtype=np.int64)}
    for k, col in enumerate(ATTACK_PACKET_COLUMNS):
        out[col] = np.where(fam == k, packets, 0)
    starts = np.concatenate([[0], np.cumsum(packets)]).astype(np.int32)
    names = pa.array(np.asarray(EFFECTS, dtype=object)[np.repeat(code, packets)].tolist(), type=pa.string())
    df = pd.DataFrame(out, index=frame.index)
    df.insert(0, "seq_effect", pd.arrays.ArrowExtensionArray(pa.ListArray.from_arrays(pa.array(starts), names)))
    return df


def _family_flows_paper(frame: pd.DataFrame, log: AttackLog) -> dict[str, np.ndarray]:
    n = len(frame)
    hits = {f: np.zeros(n, dtype=bool) for f in FAMILIES}
    src = frame["src_ip"].to_numpy(dtype=object)
    dst = frame["dst_ip"].to_numpy(dtype=object)
    for w in log.windows:
        ips = np.asarray(w.attacker_ips + w.victim_ips, dtype=object)
        hits[w.family] |= np.isin(src, ips) | np.isin(dst, ips)
    return hits


def label_flows(fl: Flows, frame: pd.DataFrame, log: AttackLog, truth: PacketTruth, mode: LabelMode = "ours",
                min_attack_fraction: float = 0.0) -> Labelled:
    """`frame` (one row per flow of `fl`) with the truth and label columns (module docstring)."""
    if mode not in LABEL_MODES:
        raise ValueError(f"unknown label mode {mode!r}; known: {', '.join(LABEL_MODES)}")
    if not 0.0 <= min_attack_fraction <= 1.0:
        raise ValueError(f"min_attack_fraction must be in [0, 1], got {min_attack_fraction}")
    out = pd.concat([frame.reset_index(drop=True), truth_columns(fl, truth)], axis=1)
    if mode == "paper":
        hits = _family_flows_paper(frame, log)
        keep = np.ones(len(out), dtype=bool)
    else:
        hits = {f: out[ATTACK_PACKET_COLUMNS[k]].to_numpy() > 0 for k, f in enumerate(FAMILIES)}
        frac = out["attack_fraction"].to_numpy()
        keep = (out["attack_packets"].to_numpy() == 0) | (frac >= min_attack_fraction)
    code = np.zeros(len(out), dtype=np.int64)
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
    return Labelled(out[keep].reset_index(drop=True), int((~keep).sum()))
