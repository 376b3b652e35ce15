"""Diversity on a synthetic dataset: a separable class far above baseline, an indistinguishable
one at baseline; CLI outputs (diversity, axes, separability)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from uavcas.analysis.axes import axis_diversity
from uavcas.analysis.diversity import DiversityOptions, diversity_table, split_by_run
from uavcas.cli import app

runner = CliRunner()


def test_separable_high_indistinguishable_at_baseline(synth_df):
    res = diversity_table(synth_df, "synth", DiversityOptions(n_boot=50, pairwise=True))
    t = res.table.set_index("class")
    for col in ("hellinger", "jsd", "hellinger_lo", "hellinger_hi", "jsd_lo", "jsd_hi", "baseline_hellinger", "baseline_jsd",
                "hellinger_pairwise", "jsd_pairwise"):
        assert t[col].between(0, 1).all(), col
    dos, worm = t.loc["DoS"], t.loc["Wormhole"]
    assert dos["hellinger"] > 0.95 and dos["jsd"] > 0.95
    # same generator as benign: at the level of the benign-vs-benign baseline (plug-in estimates
    # are biased upward on finite samples, which is why the baseline exists: compare to it, not 0)
    assert worm["hellinger"] < 2 * worm["baseline_hellinger_hi"] and worm["jsd"] < 3 * worm["baseline_jsd_hi"]
    assert dos["hellinger_lo"] > 10 * worm["hellinger_hi"]
    assert worm["hellinger_pairwise"] < 1.5 * worm["baseline_hellinger_pairwise"] < dos["hellinger_pairwise"]
    # legacy: unbounded for floods, recorded in its own columns
    assert dos["legacy_hellinger"] > 10 and worm["legacy_hellinger"] < dos["legacy_hellinger"] / 5
    edges = res.bins["synth"]
    assert edges[0] == 0.0 and len(edges) == 52


def test_baseline_split_is_by_run(synth_df):
    benign = synth_df[synth_df["label"] == "Benign"]
    a, b, by = split_by_run(benign, 0)
    assert by == "run" and not set(a["run_id"]) & set(b["run_id"]) and len(a) + len(b) == len(benign)


def test_axis_diversity_rows_and_baseline(synth_df):
    table, bins = axis_diversity(synth_df, n_boot=20)
    t = table.set_index("axis")
    assert {"n_uav", "pathloss", "mission", "tx_dbm"} <= set(t.index)
    assert (t.loc["n_uav", "low"], t.loc["n_uav", "high"]) == (5, 20)
    assert (t.loc["mission", "low"], t.loc["mission", "high"]) == ("spiral", "random")
    # swarm size moves benign timing by a factor 2 in the generator: far above its baseline
    assert t.loc["n_uav", "hellinger"] > 2 * t.loc["n_uav", "baseline_hellinger"]
    assert set(bins) == set(t.index)


def test_cli_diversity_writes_csv_and_json(synth_dir, tmp_path):
    r = runner.invoke(app, ["analyze", "diversity", str(synth_dir), "--out", str(tmp_path), "--boot", "20"])
    assert r.exit_code == 0, r.output
    df = pd.read_csv(tmp_path / "diversity.csv")
    assert len(df) == 14 and df["class"].is_unique
    for col in ("hellinger", "jsd", "hellinger_lo", "hellinger_hi", "jsd_lo", "jsd_hi", "baseline_hellinger",
                "baseline_jsd", "legacy_hellinger", "legacy_jsd"):
        assert col in df.columns
    payload = json.loads((tmp_path / "diversity.json").read_text())
    edges = np.array(payload["bins"]["ds"])
    assert edges[0] == 0 and np.all(np.diff(edges) > 0)


@pytest.mark.parametrize("make", ["missing", "not_a_dataset"])
def test_cli_bad_dataset_one_line_error(tmp_path, make):
    bad = tmp_path / "in"
    if make == "not_a_dataset":
        bad.mkdir()
        (bad / "notes.txt").write_text("hello\n")
    r = runner.invoke(app, ["analyze", "diversity", str(bad), "--out", str(tmp_path / "o")])
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert r.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error: "), r.output
    assert str(bad) in lines[0] and "Traceback" not in r.output
    assert not (tmp_path / "o").exists()  # nothing written for bad input


def test_cli_axes_and_separability(synth_dir, tmp_path):
    r = runner.invoke(app, ["analyze", "axes", str(synth_dir), "--out", str(tmp_path / "ax"), "--boot", "10"])
    assert r.exit_code == 0, r.output
    assert {"axis", "hellinger", "jsd", "baseline_hellinger", "baseline_jsd"} <= set(pd.read_csv(tmp_path / "ax" / "axes.csv").columns)
    r = runner.invoke(app, ["analyze", "separability", str(synth_dir), "--out", str(tmp_path / "sep"), "--tsne-samples", "300"])
    assert r.exit_code == 0, r.output
    stats = pd.read_csv(tmp_path / "sep" / "separability.csv").set_index("class")
    assert stats.loc["DoS", "pkt_rate_pps_mean"] > 100 * stats.loc["Benign", "pkt_rate_pps_mean"]
    for name in ("tsne.png", "distributions.png"):
        data = (tmp_path / "sep" / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list((tmp_path / "sep").glob(".*tmp*"))  # atomic writes leave no temporary file
