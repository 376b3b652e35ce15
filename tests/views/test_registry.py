"""The view registry (`uavcas.views`): names, lookups by name and by what a dataset, shard or
frame records, one-line errors, and a spec that is refused when it is not a view."""

from __future__ import annotations

from dataclasses import replace

import pandas as pd
import pytest

from uavcas.views import DEFAULT_VIEW, card_view, frame_view, names, recorded_view, register, view, views
from uavcas.views.flow import flow_view


def test_the_views_are_registered_by_name():
    assert set(names()) == {"5tuple", "hostpair", "window-hostpair", "window-host"}
    assert [v.name for v in views()] == list(names()) and DEFAULT_VIEW == "5tuple"
    flows, episodes = view("5tuple"), view("window-host")
    assert flows.row.plural == "flows" and flows.unit == "flow" and flows.is_flow and flows.key_columns == ("flow_id",)
    assert episodes.row.plural == "host-window rows" and not episodes.is_flow and episodes.flow_key == "5tuple"
    assert episodes.record_set == "host_windows" and episodes.key_columns == ("host", "window")
    assert flows.feature_set("paper") == "paper" and episodes.feature_set("paper") == "window-host-paper"


def test_an_unknown_view_is_a_one_line_error():
    with pytest.raises(ValueError, match="unknown view 'nope'; known: 5tuple"):
        view("nope")
    with pytest.raises(ValueError, match="registered twice"):
        register(flow_view("5tuple", "again"))
    with pytest.raises(ValueError, match="a name is lower-case"):
        flow_view("Bad Name", "x")
    with pytest.raises(ValueError, match="flow_key 'nope' is not one of 5tuple"):
        replace(view("5tuple"), name="other", flow_key="nope")


def test_the_view_of_a_card_shard_or_frame():
    assert card_view({"views": ["window-host"], "unit": "host-window"}).name == "window-host"
    assert card_view({"views": [], "unit": "host-window"}).name == "window-host"  # the unit, without views
    assert card_view({}).name == "5tuple"  # an import, a card before views were recorded
    assert recorded_view({"view": "hostpair"}).name == "hostpair" and recorded_view({}).name == "5tuple"
    assert frame_view(pd.DataFrame({"view": ["window-host"] * 3})).name == "window-host"
    assert frame_view(pd.DataFrame({"view": ["5tuple", "hostpair"]})).name == "5tuple"  # a mix: flows
    assert frame_view(pd.DataFrame({"x": [1]})).name == "5tuple"


def test_the_flow_labelling_options_are_refused_by_a_view_that_labels_otherwise():
    view("5tuple").check_options("paper", 0.5)
    with pytest.raises(ValueError, match="window-host view labels host-window rows from packet effects"):
        view("window-host").check_options("paper", 0.0)
