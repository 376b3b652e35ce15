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
