"""The family registry: one registered family per vocabulary family, each owning every layer's rule."""

from __future__ import annotations

import pytest

from uavcas import attacks
from uavcas.attacks import AttackFamily, families, family, register
from uavcas.attacks.base import ScheduleDraw
from uavcas.labels.label import SOURCES
from uavcas.scenario import parse
from uavcas.vocabulary import FAMILIES


def test_every_vocabulary_family_has_exactly_one_family_class():
    assert tuple(f.name for f in families()) == FAMILIES
    for name in FAMILIES:
        f = family(name)
        assert isinstance(f, AttackFamily) and f.name == name
        assert f.label_source in SOURCES
        assert f.usage.split("=")[0] == name
    assert len(attacks.SPECS) == len(FAMILIES) - 1  # dos and ddos share the flood spec


def test_unknown_family_is_refused_by_name():
    with pytest.raises(KeyError, match="teleport"):
        family("teleport")


def test_register_refuses_names_outside_the_vocabulary_and_duplicates():
    class Teleport(AttackFamily):
        name = "teleport"

    with pytest.raises(ValueError, match="vocabulary"):
        register(Teleport)
    with pytest.raises(ValueError, match="twice"):
        register(type(family("dos")))


@pytest.mark.parametrize("name", FAMILIES)
def test_each_token_parses_through_its_family_and_reads_back(name):
    tok = {"dos": "dos=250", "ddos": "ddos=500", "replay": "replay=7,0,3,1,zero", "jamming": "jamming=20",
           "mavlink_inject": "mavlink_inject=land", "gps_spoof": "gps_spoof=2.5"}.get(name, name)
    payload = "image" if "image" in family(name).payloads else family(name).payloads[0]
    sc = parse(f"{tok}-9-2-{payload}-logdist-adaptive-grid-30-95")
    (spec,) = sc.attacks
    assert spec.family == name and spec.token() == tok
    assert family(name).spec_from_params(family(name).params(spec)) == spec  # plan params -> the same spec


def test_schedule_draw_prefers_unused_uavs_and_sorts_by_node_order():
    import numpy as np

    names = [f"uav{i}" for i in range(6)]
    d = ScheduleDraw(names, "uav3", ["uav5", "uav1", "uav0", "uav2", "uav4"], None, np.random.default_rng(0))
    assert d.take(2) == ["uav1", "uav5"]
    assert d.take(1) == ["uav0"]
    assert d.take(3) == ["uav2", "uav4", "uav5"]  # the two fresh ones, then the first used one (seeded order)
    d2 = ScheduleDraw(names[:3], "uav0", ["uav1", "uav2"], None, np.random.default_rng(0))
    d2.take(2)
    assert d2.take(1) == ["uav1"]  # small swarm: reuse, in seeded order
