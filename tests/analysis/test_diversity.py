"""Diversity on a synthetic dataset: a separable class far above baseline, an indistinguishable
one at baseline (drawn at its sample size); one IAT source for every dataset; confounded axes
flagged; stratified t-SNE; CLI outputs (diversity, axes, separability)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from uavcas.analysis.axes import axis_diversity
from uavcas.analysis.diversity import DiversityOptions, diversity_table, split_by_run
from uavcas.analysis.iat import choose_source, flow_iats
from uavcas.analysis.separability import stratified_sample
from uavcas.cli import app

pytestmark = pytest.mark.slow  # a module fixture takes 10 s on 2 cores: the whole file is the full suite's

runner = CliRunner()


def test_separable_high_indistinguishable_at_baseline(synth_df):
    res = diversity_table(synth_df, "synth", DiversityOptions(n_boot=50, pairwise=True))
    t = res.table.set_index("class")
    for col in ("hellinger", "jsd", "hellinger_lo", "hellinger_hi", "jsd_lo", "jsd_hi", "baseline_hellinger",
                "baseline_jsd",
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
    assert (t.loc["n_uav", "low"], t.loc["n_uav", "high"]) == (5, 10)
    assert (t.loc["mission", "low"], t.loc["mission", "high"]) == ("spiral", "random")
    # swarm size (with what it is confounded with) moves benign timing: far above its baseline
    assert t.loc["n_uav", "hellinger"] > 2 * t.loc["n_uav", "baseline_hellinger"]
    assert set(bins) == set(t.index)
    assert (t["baseline_n_flows"] <= t["n_flows_high"]).all() and (t["baseline_n_flows"] > 0).all()


def test_confounded_axes_flagged(synth_df):
    """The medium design crosses path loss with TX power (2 x 2) but ties swarm size and mission
    to the channel setting: n_uav 5 vs 10 is also spiral vs random at 30 vs 10 dBm."""
    t = axis_diversity(synth_df, n_boot=0)[0].set_index("axis")
    flagged = {a: dict(x.split(":") for x in str(v).split(", ") if x)
               for a, v in t["confounded_with"].fillna("").items()}
    assert float(flagged["n_uav"]["mission"]) == 1.0 and float(flagged["n_uav"]["tx_dbm"]) == 1.0
    assert "tx_dbm" not in flagged["pathloss"] and "pathloss" not in flagged["tx_dbm"]
    assert "attacks" not in flagged["n_uav"]  # every setting holds every composition


def test_baseline_drawn_at_the_class_sample_size(synth_df):
    """A benign-identical class of 8 flows scores far above 0 (plug-in bias) and so does its
    baseline at 8 flows; a whole-benign baseline would call it different."""
    small = synth_df[~((synth_df["label"] == "Wormhole") & (synth_df.groupby("label").cumcount() >= 8))]
    t = diversity_table(small, "s",
                        DiversityOptions(n_boot=0, legacy=False, iat_source="flow-mean")).table.set_index("class")
    w, dos = t.loc["Wormhole"], t.loc["DoS"]
    assert w["n_flows"] == w["baseline_n_flows"] == 8
    assert w["baseline_hellinger"] > 2 * dos["baseline_hellinger"]  # the small-sample floor is higher
    assert w["hellinger"] < w["baseline_hellinger_hi"] and dos["hellinger"] > dos["baseline_hellinger_hi"]


def test_one_iat_source_for_every_dataset(synth_df):
    external_like = synth_df.drop(columns=["seq_time_s", "seq_size", "seq_flags", "seq_dir"])
    assert choose_source([synth_df, synth_df]) == "packet"
    assert choose_source([synth_df, external_like]) == "flow-mean"
    with pytest.raises(ValueError, match="flow-mean"):
        choose_source([synth_df, external_like], "packet")
    # flow-mean from the sequences: one value per flow, the mean of its packet IATs
    packet, mean = flow_iats(synth_df, source="packet"), flow_iats(synth_df, source="flow-mean")
    assert len(mean.per_flow) == len(packet.per_flow) and all(len(v) == 1 for v in mean.per_flow)
    np.testing.assert_allclose(mean.per_flow[3][0], packet.per_flow[3].mean())
    np.testing.assert_array_equal(mean.rows, packet.rows)


def test_stratified_tsne_sample_keeps_small_classes():
    labels = np.array(["DoS"] * 5000 + ["Benign"] * 600 + ["Wormhole"] * 8)
    pick = stratified_sample(labels, 300, seed=1)
    got = dict(zip(*np.unique(labels[pick], return_counts=True)))
    assert len(pick) == 300 and len(set(pick)) == 300 and got["Wormhole"] == 8
    assert got["DoS"] == got["Benign"] == 146


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
    assert {"axis", "hellinger", "jsd", "baseline_hellinger",
            "baseline_jsd"} <= set(pd.read_csv(tmp_path / "ax" / "axes.csv").columns)
    r = runner.invoke(app, ["analyze", "separability", str(synth_dir), "--out", str(tmp_path / "sep"), "--tsne-samples",
                            "300"])
    assert r.exit_code == 0, r.output
    assert pd.read_csv(tmp_path / "sep" / "tsne.csv")["label"].nunique() == 15
    stats = pd.read_csv(tmp_path / "sep" / "separability.csv").set_index("class")
    assert stats.loc["DoS", "pkt_rate_pps_mean"] > 100 * stats.loc["Benign", "pkt_rate_pps_mean"]
    for name in ("tsne.png", "distributions.png"):
        data = (tmp_path / "sep" / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list((tmp_path / "sep").glob(".*tmp*"))  # atomic writes leave no temporary file


def test_cli_one_source_with_a_dataset_without_sequences(synth_df, synth_dir, tmp_path):
    """A CICIDS2017-format CSV (per-flow mean IAT in microseconds, no packet sequences) beside our
    dataset: auto picks flow-mean for both, packet is refused."""
    cols = ["Flow Duration", "Flow IAT Mean", "Fwd IAT Mean", "Total Fwd Packets"]
    csv = synth_df[cols].copy()
    csv[["Flow Duration", "Flow IAT Mean", "Fwd IAT Mean"]] *= 1e6
    csv["Label"] = synth_df["label"].replace({"Benign": "BENIGN"})
    (tmp_path / "cic").mkdir()
    csv.to_csv(tmp_path / "cic" / "sample.csv", index=False)
    args = ["analyze", "diversity", str(synth_dir), "--reference", str(tmp_path / "cic"), "--boot", "0"]
    r = runner.invoke(app, [*args, "--out", str(tmp_path / "p"), "--iat-source", "packet"])
    assert r.exit_code == 2 and "flow-mean" in r.output and not (tmp_path / "p").exists()
    r = runner.invoke(app, [*args, "--out", str(tmp_path / "a")])
    assert r.exit_code == 0, r.output
    d = pd.read_csv(tmp_path / "a" / "diversity.csv")
    assert set(d["iat_source"]) == {"seq_time_s flow mean", "Flow IAT Mean"}
    # the same flows through both routes: the same divergences
    ours, theirs = (d[d["dataset"] == n].set_index("class")["hellinger"] for n in ("ds", "cic"))
    np.testing.assert_allclose(ours.sort_index(), theirs.sort_index(), atol=0.02)


@pytest.mark.shared
def test_cli_like_for_like_with_external(shared_data, synth_dir, tmp_path):
    ext = shared_data / "ids-samples" / "cicids2017-improved-rnd2500"
    if not ext.is_dir():
        pytest.skip(f"{ext} not found")
    r = runner.invoke(app,
                      ["analyze", "diversity", str(synth_dir), "--reference", str(ext), "--out", str(tmp_path / "p"),
                            "--iat-source", "packet"])
    assert r.exit_code == 2 and "flow-mean" in r.output and not (tmp_path / "p").exists()
    r = runner.invoke(app,
                      ["analyze", "diversity", str(synth_dir), "--reference", str(ext), "--out", str(tmp_path / "a"),
                            "--boot", "0"])
    assert r.exit_code == 0, r.output
    d = pd.read_csv(tmp_path / "a" / "diversity.csv")
    assert set(d["iat_source"]) == {"seq_time_s flow mean", "Flow IAT Mean"}
    assert (d["baseline_n_flows"] <= d["n_flows"]).all()
