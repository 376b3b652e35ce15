"""The window-host view (episodes) through extract, the dataset store and load_dataset; the
campaign's --view check; export at the authors' host-pair granularity."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from uavcas.cli import app
from uavcas.dataset.load import load_dataset
from uavcas.dataset.store import DatasetError, extract_run
from uavcas.dataset.uavcas_csv import STAT_MIN_PACKETS, read_layout
from uavcas.flows.standards import episode_feature_columns
from uavcas.schema import EPISODE_CONTEXT_FEATURES, EPISODE_PACKET_UNITS

runner = CliRunner()


def _run(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def episode_ds(synth_run_dir, tmp_path_factory):
    ds = tmp_path_factory.mktemp("ep") / "ds"
    info = extract_run(synth_run_dir, ds, view="window-host")
    return ds, info


def test_round_trip_through_the_store(episode_ds, synth_run_dir):
    ds, info = episode_ds
    card = json.loads((ds / "dataset.json").read_text())
    assert card["unit"] == "host-window" and card["views"] == ["window-host"] and card["n_flows"] == info.n_flows
    units = card["features"]["units"]
    assert set(units) == set(episode_feature_columns("cic"))
    assert units["flow_duration_us_mean"] == "us" and units["bytes_in"] == "bytes" and units["udp_share"] == "ratio"
    assert all(units[c] == u for c, u in EPISODE_PACKET_UNITS.items())
    assert card["context"]["columns"] == len(EPISODE_CONTEXT_FEATURES)
    X, y, groups, meta = load_dataset(ds, view="window-host")
    assert list(X.columns) == list(episode_feature_columns("cic")) and np.isfinite(X.to_numpy()).all()
    assert set(groups) == {"run-synth"} and (meta["view"] == "window-host").all()
    assert {"host", "host_ip", "window", "packets", "first_ts", "label_dos"} <= set(meta.columns)
    # the synthetic run's flood (uav1 -> uav0 in [20, 30) s: windows 4 and 5) at both ends
    by = meta.assign(label=y).set_index(["host", "window"]).label
    assert by[("uav0", 4)] == by[("uav0", 5)] == by[("uav1", 4)] == "DoS" and by[("uav0", 0)] == "Benign"
    assert by[("uav3", 8)] == "Blackhole" and y.value_counts().to_dict() == info.class_counts
    Xc = load_dataset(ds, context=True).X
    assert Xc.shape[1] == len(episode_feature_columns("cic")) + len(EPISODE_CONTEXT_FEATURES)
    # flows and episodes never share a dataset directory
    with pytest.raises(DatasetError, match="another --out"):
        extract_run(synth_run_dir, ds, view="5tuple", run_id="other")
    assert not (ds / "shards" / "other.parquet").exists()  # refused before anything was written
    assert json.loads((ds / "dataset.json").read_text())["views"] == ["window-host"]


def test_cli_extract_and_bogus_views(synth_run_dir, tmp_path):
    r = _run("extract", synth_run_dir, "--out", tmp_path / "ds", "--view", "window-host")
    assert r.exit_code == 0, r.output
    r = _run("extract", synth_run_dir, "--out", tmp_path / "ds2", "--view", "window-host", "--labels", "paper")
    assert r.exit_code == 2 and r.output.strip().count("\n") == 0 and not (tmp_path / "ds2").exists()
    r = _run("campaign", "run", "--out", tmp_path / "c", "--view", "bogus")
    assert r.exit_code == 2 and r.output.startswith("error: --view: 'bogus'"), r.output
    assert r.output.strip().count("\n") == 0 and not (tmp_path / "c").exists()


def test_export_writes_host_pairs(synth_run_dir, episode_ds, tmp_path):
    five, pairs = tmp_path / "five", tmp_path / "pairs"
    assert _run("extract", synth_run_dir, "--out", five).exit_code == 0
    assert _run("extract", synth_run_dir, "--out", pairs, "--view", "hostpair", "--min-packets", "1").exit_code == 0
    r = _run("export", five, "--out", tmp_path / "x5")
    assert r.exit_code == 0 and "merged into" in r.output, r.output
    assert _run("export", pairs, "--out", tmp_path / "xh").exit_code == 0
    a, b = read_layout(tmp_path / "x5").frame, read_layout(tmp_path / "xh").frame  # refuses misaligned files
    key = ["src_ip", "dst_ip"]
    # the merged 5-tuple flows hold the host-pair view's packets and classes, pair by pair
    m = a.merge(b, on=key, suffixes=("_5", "_h"))
    assert len(m) == len(a) == len(b) and (m.packets_5 == m.packets_h).all() and (m.label_5 == m.label_h).all()
    assert "DoS" in set(a.label)  # the flood's 1-3 packet flows are one pair of >= 10 packets
    # stat and ts line up row for row: the stat rows are the ts rows of >= 10 packets, in order
    stat = pd.read_csv(tmp_path / "x5" / "UAV-CAS_stat.csv")
    ts = pd.read_csv(tmp_path / "x5" / "UAV-CAS_ts.csv")
    long = ts[ts.packet_size.str.count(",") + 1 >= STAT_MIN_PACKETS].reset_index(drop=True)
    assert (stat.Label == long.Label).all() and (stat["Total Packets"] == long.packet_size.str.count(",") + 1).all()
    # episodes have no sequences: refused in one line, nothing written
    r = _run("export", episode_ds[0], "--out", tmp_path / "xe")
    assert r.exit_code == 2 and "--view hostpair" in r.output and not (tmp_path / "xe").exists()


def test_report_of_an_episode_dataset(episode_ds, tmp_path):
    from uavcas.report.dataset_report import write_report
    from uavcas.views import view

    ds, _ = episode_ds
    index = write_report(ds, tmp_path / "report")
    page = index.read_text()
    assert "Host-window features per class" in page and "host-window rows from 1 run(s)" in page
    drawn = [f for f in view("window-host").shown_features if f'alt="{f} per class"' in page]
    assert drawn and sorted(p.name for p in index.parent.iterdir()) == ["index.html"]
