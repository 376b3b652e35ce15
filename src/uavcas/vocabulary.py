"""The words of uavcas, defined once: attack families, class names, scenario axes and their values.

The scenario codec, the pydantic Literal types, the dataset's label and axis columns and the class
strings all derive from here. An attack family is one row of `ROWS` (its token, class string,
packet effect and that effect's precedence, label source) plus its module in `uavcas.attacks`;
every tuple that lists families or effects (`FAMILIES`, `FAMILY_CLASS`, `EFFECTS`,
`EFFECT_PRECEDENCE`, `ATTACK_EFFECTS`, `LABEL_SOURCES`, the label and attack-packet columns) is
derived from the rows. A mission is a name in `Mission` plus its module in `uavcas.mobility`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal, get_args

BENIGN = "Benign"
BENIGN_TOKEN = "benign"  # the scenario's attacks field of a run without attacks


@dataclass(frozen=True, kw_only=True)
class EffectRow:
    """A word of what happened to one captured packet (its ground truth, `uavcas.labels.effects`)."""

    effect: str
    # where several effects apply to one packet the one of lowest precedence wins (EFFECT_PRECEDENCE);
    # spaced by 10 so that a new effect can go between two others without renumbering
    precedence: int
    attack: bool = True  # a packet with this effect counts as an attack packet (ATTACK_EFFECTS)


@dataclass(frozen=True, kw_only=True)
class FamilyRow(EffectRow):
    """An attack family: its words, and the effect its truth rule gives (`uavcas.attacks.<module>`)."""

    token: str  # the scenario codec's token and `Attack.family`; the registry's name of its module's class
    class_name: str  # its class string in datasets (compositions join these with '+', in FAMILIES order)
    label_source: str  # the label_source part of flows its rule marks (label mode `ours`)
    # it leaves a flow's statistics near benign: the benchmark's "stealth" score is the macro-F1 over
    # the classes holding such a family (STEALTH_CLASSES)
    stealth: bool = False


# The table, append-only: one row per attack family, and the effects no family owns, in the order
# they were added. A stored effect code is a position in EFFECTS and a label_source's parts are
# ordered as LABEL_SOURCES, both in this order, so a new row goes at the end (datasets and plans
# of the rows before keep their meaning).
#
# The effects (what happened to a captured packet): an attack made it (flood, replay: an injected
# copy), the attack moved or dropped it (wormhole: carried over the attacker's detour; blackhole:
# dropped at the victim's switch), it exists only because an attack packet did (provoked), the
# channel lost it on a shaped link (channel_loss), a jammer's interference lost or slowed it on a
# jammed link (jamming), an attacker forged it as a MAVLink command (mavlink_inject), the victim's
# spoofed GPS receiver wrote it as a position report (gps_spoof), or nothing did (benign).
#
# Precedence, one effect per packet: a packet an attack made stays that packet whatever happens
# to it later (replay, flood, mavlink_inject, gps_spoof come first); one carried over a detour and
# then dropped keeps the detour (wormhole before blackhole), so both families of
# blackhole+wormhole show in its flows. A provoked packet that a blackhole drops or a wormhole
# detours shows that other family (so a blackhole+DoS victim's dropped SYN-ACK shows both families
# in its flow: the SYN is the flood's, the SYN-ACK the blackhole's); a provoked packet lost on the
# channel is still provoked (the loss is the channel's chance, the packet's existence the
# attack's). Jamming ranks below every effect that made, moved, dropped or provoked a packet
# (those say why the packet exists or where it went; the jammer only changed the channel it
# crossed) and above channel_loss: a loss on a jammed link inside the jammer's window is the
# jammer's, not chance.
ROWS: tuple[EffectRow, ...] = (
    # nothing happened to the packet
    EffectRow(effect="benign", precedence=100, attack=False),
    # SYN floods by one attacker (DoS) or two to four (DDoS): hping3's SYNs are made packets
    FamilyRow(token="dos", class_name="DoS", effect="flood", precedence=20, label_source="flood-packets"),
    FamilyRow(token="ddos", class_name="DDoS", effect="flood", precedence=20, label_source="flood-packets"),
    # an injected copy of a captured packet: made, and it ranks first (a copy stays a copy)
    FamilyRow(token="replay", class_name="Replay", effect="replay", precedence=10, label_source="replay-injections",
              stealth=True),
    # dropped at the victim's switch
    FamilyRow(token="blackhole", class_name="Blackhole", effect="blackhole", precedence=60,
              label_source="blackhole-drops", stealth=True),
    # carried over the attacker's detour
    FamilyRow(token="wormhole", class_name="Wormhole", effect="wormhole", precedence=50,
              label_source="wormhole-detour", stealth=True),
    # lost on a shaped link by the channel's chance: no attack packet
    EffectRow(effect="channel_loss", precedence=90, attack=False),
    # exists only because an attack packet did (the victim's SYN-ACK to a flood SYN, the RST answering
    # that, an ICMP error quoting an attack packet, an answer to an injected copy); it counts for the
    # family that provoked it
    EffectRow(effect="provoked", precedence=70),
    # lost or slowed by a jammer's interference on a jammed link
    FamilyRow(token="jamming", class_name="Jamming", effect="jamming", precedence=80, label_source="jamming-links"),
    # a forged MAVLink command: made, it stays the attack's whatever later carries or drops it. Quiet,
    # but scored per class: the stealth score keeps the paper's three families, comparable across versions
    FamilyRow(token="mavlink_inject", class_name="MAVLinkInjection", effect="mavlink_inject", precedence=30,
              label_source="mavlink-injections"),
    # a position report the victim's spoofed GPS receiver wrote: its content is the attack's (made);
    # quiet too, and scored per class as mavlink_inject
    FamilyRow(token="gps_spoof", class_name="GPSSpoofing", effect="gps_spoof", precedence=40,
              label_source="gps-spoof-reports"),
)
FAMILY_ROWS: dict[str, FamilyRow] = {r.token: r for r in sorted((r for r in ROWS if isinstance(r, FamilyRow)),
                                                               key=lambda r: r.token)}


def _check_rows(rows: tuple[EffectRow, ...]) -> dict[str, EffectRow]:
    """The table's rules: one row per token and class; one precedence per effect and one effect per
    precedence; tokens the codec can read. Returns each effect's first row."""
    fams = [r for r in rows if isinstance(r, FamilyRow)]
    for what, values in (("token", [r.token for r in fams]), ("class name", [r.class_name for r in fams])):
        twice = sorted({x for x in values if values.count(x) > 1})
        if twice:
            raise ValueError(f"vocabulary.ROWS: {what} {twice[0]!r} in two rows")
    for r in fams:
        if not re.fullmatch(r"[a-z][a-z0-9_]*", r.token) or r.token == BENIGN_TOKEN:
            raise ValueError(f"vocabulary.ROWS: token {r.token!r} must be lowercase letters, digits and '_' "
                             f"(the codec splits on '+', '=' and '-') and not {BENIGN_TOKEN!r}")
        if "+" in r.class_name or r.class_name == BENIGN:
            raise ValueError(f"vocabulary.ROWS: class name {r.class_name!r} must not hold '+' nor be {BENIGN!r}")
    by_effect: dict[str, EffectRow] = {}
    for r in rows:
        first = by_effect.setdefault(r.effect, r)
        if (first.precedence, first.attack) != (r.precedence, r.attack):
            raise ValueError(f"vocabulary.ROWS: effect {r.effect!r} with two precedences or attack flags")
    ranks = [r.precedence for r in by_effect.values()]
    if len(set(ranks)) != len(ranks):
        raise ValueError("vocabulary.ROWS: two effects share a precedence (one effect per packet)")
    return by_effect


_EFFECT_ROW = _check_rows(ROWS)

# Attack families in canonical (alphabetical) order. The scenario codec orders attack tokens this
# way, and class strings of compositions join in this order, which is also the order of the paper's
# composition names (Blackhole+DoS, DDoS+Replay, ...).
FAMILIES: tuple[str, ...] = tuple(FAMILY_ROWS)
Family = Literal[FAMILIES]  # type: ignore[valid-type]  # built from the table; pydantic reads it at run time
FAMILY_CLASS: dict[str, str] = {f: r.class_name for f, r in FAMILY_ROWS.items()}
# What happened to one captured packet (the rows' effects, in table order: stored codes index this).
EFFECTS: tuple[str, ...] = tuple(dict.fromkeys(r.effect for r in ROWS))
Effect = Literal[EFFECTS]  # type: ignore[valid-type]
# One effect per packet: where several apply, the first of this order wins (the table's comment says why).
EFFECT_PRECEDENCE: tuple[str, ...] = tuple(sorted(EFFECTS, key=lambda e: _EFFECT_ROW[e].precedence))
# count as attack packets (the family that made, moved, dropped or provoked them)
ATTACK_EFFECTS: tuple[str, ...] = tuple(e for e in EFFECTS if _EFFECT_ROW[e].attack)
# The label_source parts of the families' rules, in table order (labels.label.SOURCES adds the paper's).
LABEL_SOURCES: tuple[str, ...] = tuple(dict.fromkeys(r.label_source for r in ROWS if isinstance(r, FamilyRow)))
LABEL_COLUMNS: tuple[str, ...] = tuple(f"label_{f}" for f in FAMILIES)
# Per-family counts of attack packets in a flow (the family whose attack gave the packet its effect).
ATTACK_PACKET_COLUMNS: tuple[str, ...] = tuple(f"attack_packets_{f}" for f in FAMILIES)

# Payloads are not listed here: each is a composition of traffic apps, one table in
# uavcas.traffic.payloads (the codec's Scenario.payload is checked against it).
# Path-loss models are not listed here: their names are the registry's (uavcas.channel.pathloss),
# one module per model; the codec's Scenario.pathloss is checked against it.
Mission = Literal["spiral", "grid", "hover_transit", "random"]
MISSIONS: tuple[str, ...] = get_args(Mission)
# How flows are labelled: ours (from each packet's effect, uavcas.labels) or paper (the authors' IP
# membership of attackers and victims, for comparison)
LabelMode = Literal["ours", "paper"]
LABEL_MODES: tuple[str, ...] = get_args(LabelMode)
# What a campaign does with a run whose fidelity audit failed: keep it flagged, or retry it
FidelityPolicy = Literal["flag", "retry"]
FIDELITY_POLICIES: tuple[str, ...] = get_args(FidelityPolicy)
# Where the torch baselines train: auto = CUDA when torch sees a GPU, else the CPU
TorchDevice = Literal["auto", "cpu", "cuda"]
TORCH_DEVICES: tuple[str, ...] = get_args(TorchDevice)
SeqMode = Literal["inc", "rand", "zero"]  # how a replayer rewrites TCP sequence numbers
SEQ_MODES: tuple[str, ...] = get_args(SeqMode)

# The paper's 9 '-'-separated fields of a scenario string, in order.
FIELD_NAMES: tuple[str, ...] = (
    "attacks",
    "n_uav",
    "n_bs",
    "payload",
    "pathloss",
    "modulation",
    "mission",
    "tx_dbm",
    "noise",
)
# The same axes as dataset columns: the noise floor is stored signed, in dBm.
AXIS_COLUMNS: tuple[str, ...] = FIELD_NAMES[:-1] + ("noise_dbm",)


def canonical_families(families) -> tuple[str, ...]:
    """The families in canonical order; unknown names are refused."""
    fams = set(families)
    unknown = fams - set(FAMILIES)
    if unknown:
        raise ValueError(f"unknown attack family {sorted(unknown)}; known: {list(FAMILIES)}")
    return tuple(f for f in FAMILIES if f in fams)


def class_name(families: set[str] | list[str] | tuple[str, ...]) -> str:
    """Canonical class string of a set of families: 'Benign', 'DoS', 'Blackhole+DoS', ..."""
    fams = canonical_families(families)
    return "+".join(FAMILY_CLASS[f] for f in fams) if fams else BENIGN


def _check_pairs(pairs: tuple[tuple[str, str], ...]) -> None:
    """Each pair: two known families in canonical order, and no pair twice."""
    for p in pairs:
        if len(p) != 2 or p != canonical_families(p) or len(set(p)) != 2:
            raise ValueError(f"vocabulary.PAIRS: {p} is not two distinct families in canonical order")
    if len(set(pairs)) != len(pairs):
        raise ValueError("vocabulary.PAIRS: a pair appears twice")


# The classes: the paper's 15 (Benign, its 5 singles, 9 complementary pairs) and each family
# added since as a single (its compositions are in PAIRS once a preset draws them). Append-only
# too: the classes' order is the order of the dataset card's classes and of the benchmark's labels.
PAIRS: tuple[tuple[str, str], ...] = (
    ("blackhole", "dos"),
    ("blackhole", "ddos"),
    ("dos", "wormhole"),
    ("ddos", "wormhole"),
    ("blackhole", "wormhole"),
    ("blackhole", "replay"),
    ("ddos", "replay"),
    ("dos", "replay"),
    ("replay", "wormhole"),
    # the medium preset's compositions of the families added since (scenario.campaign.NEW_FAMILY_COMPOSITIONS)
    ("blackhole", "jamming"),
    ("dos", "jamming"),
    ("gps_spoof", "wormhole"),
    ("ddos", "gps_spoof"),
    ("blackhole", "mavlink_inject"),
    ("mavlink_inject", "replay"),
)
_check_pairs(PAIRS)
CLASSES: tuple[str, ...] = (
    (BENIGN,) + tuple(FAMILY_CLASS[f] for f in FAMILIES) + tuple(class_name(p) for p in PAIRS)
)
assert len(CLASSES) == len(set(CLASSES)) == 1 + len(FAMILIES) + len(PAIRS)

# Families that leave a flow's statistics near benign (no flood, `FamilyRow.stealth`): the
# benchmark's "stealth" score is the macro-F1 over the classes holding one of them (3 singles + the
# 9 paper pairs + 4 of the new families' pairs, 16 classes).
STEALTH_FAMILIES: tuple[str, ...] = tuple(f for f in FAMILIES if FAMILY_ROWS[f].stealth)
STEALTH_CLASSES: tuple[str, ...] = tuple(
    class_name(fams) for fams in [(f,) for f in FAMILIES] + list(PAIRS) if set(fams) & set(STEALTH_FAMILIES)
)


def families_of(attacks_field: str) -> tuple[str, ...]:
    """Families of a scenario's attacks field, canonical order: 'blackhole+dos=1000' -> ('blackhole', 'dos').

    Lenient on purpose (datasets from older codec versions): unknown tokens are dropped.
    """
    names = {tok.split("=", 1)[0].strip().lower() for tok in str(attacks_field).split("+")}
    return tuple(f for f in FAMILIES if f in names)
