"""The paper's 9-field scenario string and its typed form.

`<attacks>-<n_uav>-<n_bs>-<payload>-<pathloss>-<modulation>-<mission>-<tx_dbm>-<noise>`, e.g.
`blackhole+dos=1000-20-2-image-logdist-adaptive-random-30-95` (noise 95 means -95 dBm).
The words come from `uavcas.vocabulary`; each attack token is parsed by its family
(`uavcas.attacks`) into the typed form (`uavcas.scenario_model`). The form is canonical: attack
tokens are ordered as the vocabulary orders
the families, so `dos=1000+blackhole-...` is normalised to `blackhole+dos=1000-...` (the same
scenario, hence the same plan). Any other deviation (leading zeros, ...) is refused with a
one-line `ScenarioError` naming the field at fault.
"""

from __future__ import annotations

from uavcas.attacks import family
from uavcas.channel.pathloss import names as pathloss_names
from uavcas.scenario_model import MCS_LEVEL, Scenario, ScenarioError, choice, int_field
from uavcas.traffic.payloads import PAYLOAD_NAMES
from uavcas.vocabulary import BENIGN_TOKEN, FAMILIES, FIELD_NAMES, MISSIONS

__all__ = ["FIELD_NAMES", "Scenario", "ScenarioError", "attacks_of", "canonical", "parse"]


def _parse_attack(tok: str):
    name, eq, arg = tok.partition("=")
    if name not in FAMILIES:
        forms = ", ".join([BENIGN_TOKEN] + [family(f).usage for f in FAMILIES])
        raise ScenarioError(f"field 'attacks': unknown attack token {tok!r} ({forms})")
    spec = family(name).parse(arg if eq else None, tok)
    if spec.token() != tok:  # e.g. leading zeros; the token must read back as written
        raise ScenarioError(f"field 'attacks': {tok!r} is not in canonical form ({spec.token()!r})")
    return spec


def attacks_of(field: str) -> tuple:
    """The specs of a scenario's attacks field ('benign' -> ()), in canonical order."""
    if field == BENIGN_TOKEN:
        return ()
    toks = field.split("+")
    if any(t == "" for t in toks):
        raise ScenarioError(f"field 'attacks': empty token in {field!r}")
    if BENIGN_TOKEN in toks:
        raise ScenarioError(f"field 'attacks': '{BENIGN_TOKEN}' cannot be combined with attacks")
    attacks = tuple(_parse_attack(t) for t in toks)
    fams = [a.family for a in attacks]
    if len(set(fams)) != len(fams):
        raise ScenarioError(f"field 'attacks': a family appears twice in {field!r}")
    groups: dict[str, list[str]] = {}
    for f in fams:
        if family(f).exclusive_group is not None:
            groups.setdefault(family(f).exclusive_group, []).append(f)
    for same in groups.values():
        if len(same) > 1:
            raise ScenarioError(f"field 'attacks': {' and '.join(sorted(same))} cannot be combined (use one)")
    return tuple(sorted(attacks, key=lambda a: FAMILIES.index(a.family)))


def parse(text: str) -> Scenario:
    """The scenario of `text`; an out-of-order attack field is normalised (see `canonical`)."""
    if not isinstance(text, str) or not text:
        raise ScenarioError("scenario: empty string")
    fields = text.split("-")
    if len(fields) != len(FIELD_NAMES):
        raise ScenarioError(
            f"scenario: expected {len(FIELD_NAMES)} '-'-separated fields "
            f"({'-'.join(FIELD_NAMES)}), got {len(fields)} in {text!r}"
        )
    raw = dict(zip(FIELD_NAMES, fields))
    attacks = attacks_of(raw["attacks"])
    modulation = raw["modulation"]
    if modulation != "adaptive" and not MCS_LEVEL.match(modulation):
        raise ScenarioError(
            f"field 'modulation': {modulation!r} is not 'adaptive' or a fixed level mcs0..mcs6"
        )
    n_uav = int_field("n_uav", raw["n_uav"], 1, 250)
    for a in attacks:
        need = family(a.family).min_uavs
        if n_uav < need:
            raise ScenarioError(f"field 'n_uav': {a.family} needs at least {need} UAVs (attackers + victim)")
    payload = choice("payload", raw["payload"], PAYLOAD_NAMES)
    for a in attacks:  # a family acts only on the traffic of some payloads (AttackFamily.payloads)
        fam = family(a.family)
        if payload not in fam.payloads:
            why = f" ({fam.payloads_why})" if fam.payloads_why else ""
            raise ScenarioError(f"field 'payload': {a.family} needs payload {' or '.join(fam.payloads)}{why}, "
                                f"got {payload!r}")
    sc = Scenario(
        attacks=attacks,
        n_uav=n_uav,
        n_bs=int_field("n_bs", raw["n_bs"], 1, 16),
        payload=payload,
        pathloss=choice("pathloss", raw["pathloss"], pathloss_names()),
        modulation=modulation,
        mission=choice("mission", raw["mission"], MISSIONS),
        tx_dbm=int_field("tx_dbm", raw["tx_dbm"], 0, 60),
        noise=int_field("noise", raw["noise"], 30, 200),
    )
    # Only the order of attack tokens may differ from the canonical form; e.g. leading zeros are
    # refused by int_field already (belt and braces).
    expected = "-".join([sc.attacks_token] + fields[1:])
    if sc.to_string() != expected:
        raise ScenarioError(f"scenario: {text!r} is not in canonical form ({sc.to_string()!r})")
    return sc


def canonical(text: str) -> str:
    """The canonical form of a scenario string (attack tokens in vocabulary order)."""
    return parse(text).to_string()
