"""The words of uavcas, defined once: attack families, class names, scenario axes and their values.

The scenario codec, the pydantic Literal types, the dataset's label and axis columns and the class
strings all derive from here, so adding a family or a mission means editing this module (plus the
family's own module in `uavcas.attacks`, or the mission's in `uavcas.mobility`).
"""

from __future__ import annotations

from typing import Literal, get_args

# Attack families in canonical (alphabetical) order. The scenario codec orders attack tokens this
# way, and class strings of compositions join in this order, which is also the order of the paper's
# composition names (Blackhole+DoS, DDoS+Replay, ...).
Family = Literal["blackhole", "ddos", "dos", "gps_spoof", "jamming", "mavlink_inject", "replay", "wormhole"]
FAMILIES: tuple[str, ...] = get_args(Family)
FAMILY_CLASS: dict[str, str] = {
    "blackhole": "Blackhole",
    "ddos": "DDoS",
    "dos": "DoS",
    "gps_spoof": "GPSSpoofing",
    "jamming": "Jamming",
    "mavlink_inject": "MAVLinkInjection",
    "replay": "Replay",
    "wormhole": "Wormhole",
}
BENIGN = "Benign"
BENIGN_TOKEN = "benign"  # the scenario's attacks field of a run without attacks

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

LABEL_COLUMNS: tuple[str, ...] = tuple(f"label_{f}" for f in FAMILIES)

# What happened to one captured packet (its ground truth; `uavcas.labels.effects`): an attack
# made it (flood, replay: an injected copy), the attack moved or dropped it (wormhole: carried
# over the attacker's detour; blackhole: dropped at the victim's switch), it exists only because
# an attack packet did (provoked: the victim's SYN-ACK to a flood SYN, the RST answering that,
# an ICMP error quoting an attack packet, an answer to an injected copy), the channel lost it on
# a shaped link (channel_loss), a jammer's interference lost or slowed it on a jammed link
# (jamming), an attacker forged it as a MAVLink command (mavlink_inject), the victim's spoofed GPS
# receiver wrote it as a position report (gps_spoof: its content is the attack's), or nothing did
# (benign). New words go at the end: stored effect codes keep their meaning.
Effect = Literal["benign", "flood", "replay", "blackhole", "wormhole", "channel_loss", "provoked", "jamming",
                 "mavlink_inject", "gps_spoof"]
EFFECTS: tuple[str, ...] = get_args(Effect)
# One effect per packet: where several apply, the first of this order wins. A packet an attack
# made stays that packet whatever happens to it later; one carried over a detour and then dropped
# keeps the detour, so both families of blackhole+wormhole show in its flows. A provoked packet
# that a blackhole drops or a wormhole detours shows that other family (so a blackhole+DoS
# victim's dropped SYN-ACK shows both families in its flow: the SYN is the flood's, the SYN-ACK
# the blackhole's); a provoked packet lost on the channel is still provoked (the loss is the
# channel's chance, the packet's existence the attack's). mavlink_inject and gps_spoof sit with the
# other "made" effects (replay, flood): a forged command or a spoofed report stays the attack's
# whatever later carries or drops it. Jamming ranks below every effect that made, moved, dropped or
# provoked a packet (those say why the packet exists or where it went; the jammer only changed the
# channel it crossed) and above channel_loss: a loss on a jammed link inside the jammer's window is
# the jammer's, not chance.
EFFECT_PRECEDENCE: tuple[str, ...] = (
    "replay", "flood", "mavlink_inject", "gps_spoof", "wormhole", "blackhole", "provoked", "jamming",
    "channel_loss", "benign",
)  # fmt: skip
# count as attack packets (the family that made, moved, dropped or provoked them)
ATTACK_EFFECTS: tuple[str, ...] = ("flood", "replay", "blackhole", "wormhole", "provoked", "jamming", "mavlink_inject",
                                   "gps_spoof")
# Per-family counts of attack packets in a flow (the family whose attack gave the packet its effect).
ATTACK_PACKET_COLUMNS: tuple[str, ...] = tuple(f"attack_packets_{f}" for f in FAMILIES)


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


# The classes: the paper's 15 (Benign, its 5 singles, 9 complementary pairs) and each family
# added since as a single (its compositions are in PAIRS once a preset draws them).
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
CLASSES: tuple[str, ...] = (
    (BENIGN,) + tuple(FAMILY_CLASS[f] for f in FAMILIES) + tuple(class_name(p) for p in PAIRS)
)
assert len(CLASSES) == len(set(CLASSES)) == 1 + len(FAMILIES) + len(PAIRS)

# Families that leave a flow's statistics near benign (no flood): the benchmark's "stealth" score
# is the macro-F1 over the classes holding one of them (3 singles + the 9 paper pairs + 4 of the
# new families' pairs, 16 classes). The paper's three, kept as they were so that the score stays
# comparable across versions: gps_spoof and mavlink_inject are quiet too, and are scored per class.
STEALTH_FAMILIES: tuple[str, ...] = ("blackhole", "replay", "wormhole")
STEALTH_CLASSES: tuple[str, ...] = tuple(
    class_name(fams) for fams in [(f,) for f in FAMILIES] + list(PAIRS) if set(fams) & set(STEALTH_FAMILIES)
)


def families_of(attacks_field: str) -> tuple[str, ...]:
    """Families of a scenario's attacks field, canonical order: 'blackhole+dos=1000' -> ('blackhole', 'dos').

    Lenient on purpose (datasets from older codec versions): unknown tokens are dropped.
    """
    names = {tok.split("=", 1)[0].strip().lower() for tok in str(attacks_field).split("+")}
    return tuple(f for f in FAMILIES if f in names)
