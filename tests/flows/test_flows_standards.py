"""The feature-standard registry (`uavcas.flows.standards`): names, refusals, record checks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from typer.testing import CliRunner

from helpers.pcapgen import http_session, syn_flood, write
from uavcas.cli import app
from uavcas.flows import assemble, read_packets
from uavcas.flows.features import flow_frame
from uavcas.flows.standards import DEFAULT_STANDARD, FlowPackets, feature_columns, names, standard, standards


def test_the_registry_holds_one_record_per_module_with_its_own_units():
    assert names() == ("cic", "paper") and DEFAULT_STANDARD in names()
    assert [s.module for s in standards()] == [f"uavcas.flows.standards.{n}" for n in names()]
    cic, paper = standard("cic"), standard("paper")
    assert cic.units["Flow Duration"] == "us" and paper.units["Flow Duration"] == "s"
    assert len(cic.columns) == len(paper.columns) == 47 and feature_columns("paper") == paper.columns
    assert cic.episode_units["flow_duration_us_max"] == "us" and paper.episode_units["flow_duration_s_mean"] == "s"


def test_an_unknown_standard_is_one_line_listing_the_registered_ones(tmp_path):
    with pytest.raises(ValueError, match=r"^unknown feature standard 'x'; known: cic, paper$"):
        standard("x")
    pcap = write(tmp_path / "a.pcap", http_session())
    p = read_packets([pcap])
    with pytest.raises(ValueError, match="unknown feature standard"):
        flow_frame(p, assemble(p), standard="x")
    res = CliRunner().invoke(app, ["flows", str(pcap), "--features", "x"])
    assert res.exit_code != 0 and "'cic', 'paper'" in res.output and "Traceback" not in res.output


def test_a_record_that_does_not_describe_every_column_is_refused():
    cic = standard("cic")
    short = dict(cic.units)
    short.pop("Idle Max")
    with pytest.raises(ValueError, match="units do not cover exactly its columns"):
        dataclasses.replace(cic, name="broken", units=short)
    with pytest.raises(ValueError, match="episode_summary names columns it lacks"):
        dataclasses.replace(cic, name="broken", episode_summary={"nope": "nope_s"})
    with pytest.raises(ValueError, match="a name is"):
        dataclasses.replace(cic, name="Bad Name")


def test_flow_frame_holds_the_standards_columns_in_order_from_its_compute(tmp_path):
    pcap = write(tmp_path / "a.pcap", http_session() + syn_flood(n=5))
    p = read_packets([pcap])
    fl = assemble(p)
    for std in standards():
        df = flow_frame(p, fl, standard=std.name)
        assert list(df.columns[-len(std.columns):]) == list(std.columns) and df.attrs["feature_standard"] == std.name
        assert df[list(std.columns)].dtypes.eq(np.float64).all()


def test_a_compute_that_returns_other_columns_is_refused(tmp_path):
    cic = standard("cic")
    odd = dataclasses.replace(cic, name="odd", compute=lambda fp: {"x": np.zeros(fp.flows.n_flows)})
    pcap = write(tmp_path / "a.pcap", http_session())
    p = read_packets([pcap])
    fp = FlowPackets(p, assemble(p), np.array(["10.0.0.1"]), np.array(["10.0.0.2"]))
    with pytest.raises(ValueError, match="computed"):
        odd.features(fp)


def test_the_cli_offers_every_registered_standard_with_its_summary():
    res = CliRunner().invoke(app, ["extract", "--help"], terminal_width=200)
    text = " ".join(res.output.replace("│", " ").split())  # help wrapped in a rich panel
    assert res.exit_code == 0 and "|".join(names()) in text
    assert all(f"{s.name} ({s.summary})" in text for s in standards())
