"""The vocabulary is the one source of families, classes and axes; everything else derives from it."""

from __future__ import annotations

import typing

import pytest

from uavcas import schema
from uavcas import vocabulary as v
from uavcas.scenario import Scenario, parse
from uavcas.scenario.codec import FIELD_NAMES


def test_codec_literals_and_dataset_columns_derive_from_the_vocabulary():
    assert FIELD_NAMES is v.FIELD_NAMES
    fields = Scenario.model_fields
    assert typing.get_args(fields["mission"].annotation) == v.MISSIONS
    assert schema.FAMILIES is v.FAMILIES and schema.CLASSES is v.CLASSES and schema.AXIS_COLUMNS is v.AXIS_COLUMNS
    assert schema.LABEL_COLUMNS == tuple(f"label_{f}" for f in v.FAMILIES)
    sc = parse("blackhole+dos=1000-5-2-image-logdist-adaptive-grid-30-95")
    assert tuple(sc.axes()) == v.AXIS_COLUMNS


def test_pathloss_names_come_from_the_registry_alone():
    # The vocabulary holds no list of path-loss names: Scenario.pathloss is checked against the registry.
    from pydantic import ValidationError

    from uavcas.channel.pathloss import names

    assert not any(n.upper().startswith("PATHLOSS") for n in dir(v))
    assert set(names()) >= {"logdist", "3gpp", "tworay", "freespace"}
    for n in names():
        assert Scenario(n_uav=3, n_bs=1, pathloss=n).pathloss == n
    with pytest.raises(ValidationError, match="unknown path-loss model 'okumura'; registered: "):
        Scenario(n_uav=3, n_bs=1, pathloss="okumura")


def test_families_are_canonical_and_classes_join_in_that_order():
    assert list(v.FAMILIES) == sorted(v.FAMILIES)
    assert v.class_name(["dos", "blackhole"]) == "Blackhole+DoS" == v.class_name(("blackhole", "dos"))
    assert v.class_name([]) == v.BENIGN
    assert len(v.CLASSES) == len(set(v.CLASSES)) == 1 + len(v.FAMILIES) + len(v.PAIRS)
    paper = {"Benign", "Blackhole", "DDoS", "DoS", "Replay", "Wormhole"} | {v.class_name(p) for p in v.PAIRS[:9]}
    assert len(paper) == 15 and paper <= set(v.CLASSES)  # the paper's 15 classes are all there, its pairs first
    assert v.CLASSES[:1] == (v.BENIGN,) and {"GPSSpoofing", "Jamming", "MAVLinkInjection"} <= set(v.CLASSES)
    with pytest.raises(ValueError, match="teleport"):
        v.class_name(["teleport"])


def test_families_of_an_attacks_field():
    assert v.families_of("replay=50,200,10,5,inc+ddos=1000") == ("ddos", "replay")
    assert v.families_of("benign") == ()


# What datasets and plans written so far hold (issue 40): the tuples derived from the table must
# stay these, so a row may only be appended, and a new row's words must not move these.
PINNED = {
    "FAMILIES": ("blackhole", "ddos", "dos", "gps_spoof", "jamming", "mavlink_inject", "replay", "wormhole"),
    "EFFECTS": ("benign", "flood", "replay", "blackhole", "wormhole", "channel_loss", "provoked", "jamming",
                "mavlink_inject", "gps_spoof"),
    "EFFECT_PRECEDENCE": ("replay", "flood", "mavlink_inject", "gps_spoof", "wormhole", "blackhole", "provoked",
                          "jamming", "channel_loss", "benign"),
    "ATTACK_EFFECTS": ("flood", "replay", "blackhole", "wormhole", "provoked", "jamming", "mavlink_inject",
                       "gps_spoof"),
    "LABEL_SOURCES": ("flood-packets", "replay-injections", "blackhole-drops", "wormhole-detour", "jamming-links",
                      "mavlink-injections", "gps-spoof-reports"),
    "STEALTH_FAMILIES": ("blackhole", "replay", "wormhole"),
    "CLASSES": ("Benign", "Blackhole", "DDoS", "DoS", "GPSSpoofing", "Jamming", "MAVLinkInjection", "Replay",
                "Wormhole", "Blackhole+DoS", "Blackhole+DDoS", "DoS+Wormhole", "DDoS+Wormhole", "Blackhole+Wormhole",
                "Blackhole+Replay", "DDoS+Replay", "DoS+Replay", "Replay+Wormhole", "Blackhole+Jamming",
                "DoS+Jamming", "GPSSpoofing+Wormhole", "DDoS+GPSSpoofing", "Blackhole+MAVLinkInjection",
                "MAVLinkInjection+Replay"),
}


def test_the_tuples_derived_from_the_table_are_those_datasets_hold():
    from uavcas.labels.label import PAPER_SOURCE, SOURCES

    for name, value in PINNED.items():
        assert getattr(v, name) == value, name
    assert v.FAMILY_CLASS == dict(zip(PINNED["FAMILIES"], ("Blackhole", "DDoS", "DoS", "GPSSpoofing", "Jamming",
                                                           "MAVLinkInjection", "Replay", "Wormhole")))
    assert v.LABEL_COLUMNS == tuple(f"label_{f}" for f in PINNED["FAMILIES"])
    assert v.ATTACK_PACKET_COLUMNS == tuple(f"attack_packets_{f}" for f in PINNED["FAMILIES"])
    assert SOURCES == PINNED["LABEL_SOURCES"] + (PAPER_SOURCE,) and PAPER_SOURCE == "ip-membership"
    # the Literal types are the table's, usable at run time (pydantic validates against them)
    assert typing.get_args(v.Family) == v.FAMILIES and typing.get_args(v.Effect) == v.EFFECTS


def test_a_family_reads_its_words_from_its_row():
    from uavcas.attacks import families

    assert {f.name for f in families()} == set(v.FAMILIES)
    for f in families():
        row = v.FAMILY_ROWS[f.name]
        assert (f.effect, f.label_source, f.class_name) == (row.effect, row.label_source, v.FAMILY_CLASS[f.name])
    assert v.FAMILY_ROWS["ddos"].effect == v.FAMILY_ROWS["dos"].effect == "flood"


@pytest.mark.parametrize("row, message", [
    (v.FamilyRow(token="dos", class_name="DoS2", effect="x", precedence=5, label_source="x"), "token 'dos' in two"),
    (v.FamilyRow(token="dos2", class_name="DoS", effect="x", precedence=5, label_source="x"), "class name 'DoS'"),
    (v.FamilyRow(token="Bad-Token", class_name="B", effect="x", precedence=5, label_source="x"), "token 'Bad-Token'"),
    (v.FamilyRow(token="syn", class_name="Syn", effect="flood", precedence=5, label_source="x"), "effect 'flood'"),
    (v.FamilyRow(token="syn", class_name="Syn", effect="syn", precedence=20, label_source="x"), "share a precedence"),
    (v.FamilyRow(token="syn", class_name="A+B", effect="syn", precedence=5, label_source="x"), r"must not hold '\+'"),
])
def test_the_table_refuses_a_row_that_breaks_its_rules(row, message):
    with pytest.raises(ValueError, match=message):
        v._check_rows(v.ROWS + (row,))


def test_an_appended_row_keeps_the_words_before_it():
    row = v.FamilyRow(token="syn", class_name="Syn", effect="syn", precedence=25, label_source="syn-packets")
    ranks = v._check_rows(v.ROWS + (row,))
    assert list(ranks)[:len(v.EFFECTS)] == list(v.EFFECTS) and list(ranks)[-1] == "syn"


def test_pairs_are_checked_against_the_families():
    with pytest.raises(ValueError, match="canonical order"):
        v._check_pairs((("dos", "blackhole"),))
    with pytest.raises(ValueError, match="teleport"):
        v._check_pairs((("blackhole", "teleport"),))
    with pytest.raises(ValueError, match="twice"):
        v._check_pairs((("blackhole", "dos"), ("blackhole", "dos")))
