"""The one reader: every format detected from the path and read to our names, bad input refused."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest
from typer.testing import CliRunner

from helpers.synth_run import build_run
from uavcas.cli import app
from uavcas.dataset.read import FORMATS, detect_format, load_any, select_view
from uavcas.dataset.uavcas_csv import layout_rows
from uavcas.flows.standards.cic import FEATURES
from uavcas.flows.standards.paper import PAPER_FEATURES

runner = CliRunner()

CIC = (" Destination Port, Flow Duration, Total Fwd Packets, Flow IAT Mean, Label\n"
       "80,2000000,3,500000,BENIGN\n443,1000,1,0,DDoS\n")
UNSW = "id,dur,spkts,dpkts,sbytes,dbytes,attack_cat,label\n1,0.1,2,2,100,100,Normal,0\n2,0.2,4,0,400,0,DoS,1\n"


@pytest.fixture(scope="module")
def dataset_and_csv(synth_run_dir, tmp_path_factory):
    root = tmp_path_factory.mktemp("read")
    ds, csv = root / "ds", root / "csv"
    extra = [build_run(root / name, run_id=name) for name in ("run-two", "run-three")]
    for run in (synth_run_dir, *extra):
        assert runner.invoke(app, ["extract", str(run), "--out", str(ds)]).exit_code == 0
    r = runner.invoke(app, ["export", str(ds), "--format", "uavcas-csv", "--out", str(csv)])
    assert r.exit_code == 0, r.output
    return ds, csv


def test_ours_and_the_authors_csv_give_the_same_flows(dataset_and_csv, tmp_path):
    ds, csv = dataset_and_csv
    assert detect_format(ds) == detect_format(ds / "flows.parquet") == "uavcas"
    assert (detect_format(csv) == detect_format(csv / "UAV-CAS_ts.csv") == detect_format(csv / "UAV-CAS_stat.csv")
            == "uavcas-csv")
    ours, theirs = load_any(ds), load_any(csv)
    assert ours.attrs["source"] == "uavcas" and theirs.attrs["source"] == "uavcas-csv"
    assert ours.attrs["feature_standard"] == "cic" and theirs.attrs["feature_standard"] == "paper"
    # the layout holds host pairs (export merges the 5-tuple flows) of >= 2 packets, in order, with their labels
    pairs, _ = layout_rows(ours)
    assert len(pairs) < len(ours) and pairs.packets.sum() == ours.packets.sum()
    kept = pairs[pairs.packets >= 2].reset_index(drop=True)
    assert theirs["label"].tolist() == kept["label"].tolist()
    assert theirs["packets"].tolist() == kept["packets"].tolist()
    # the stat rows (>= 10 packets) carry a run id (config_idx = the run's rank here) and features
    long = theirs[theirs.packets >= 10]
    assert long["run_id"].nunique() == 3 and long["Total Packets"].tolist() == long["packets"].tolist()
    assert theirs.attrs["absent_features"] == [] and "src_port" in theirs.attrs["lacks"]
    # the ts file alone: sequences, no features, and said to be
    (tmp_path / "only").mkdir()
    shutil.copy(csv / "UAV-CAS_ts.csv", tmp_path / "only")
    alone = load_any(tmp_path / "only")
    assert alone.attrs["absent_features"] == list(PAPER_FEATURES) and len(alone) == len(theirs)


def test_external_samples_get_our_names_and_one_group_per_row(tmp_path):
    (tmp_path / "cic").mkdir()
    (tmp_path / "cic" / "a.csv").write_text(CIC)
    (tmp_path / "unsw.csv").write_text(UNSW)
    cic = load_any(tmp_path / "cic")
    assert cic.attrs["source"] == "cicids2017" and cic["label"].tolist() == ["Benign", "DDoS"]
    assert cic["Flow Duration"].tolist() == [2_000_000, 1000] and cic["run_id"].is_unique
    assert "Fwd Header Length" in cic.attrs["absent_features"] and "Flow Duration" not in cic.attrs["absent_features"]
    unsw = load_any(tmp_path / "unsw.csv")
    assert unsw.attrs["source"] == "unsw-nb15" and unsw["label"].tolist() == ["Benign", "DoS"]
    # an explicit format overrides detection, and a wrong one fails with the file named
    with pytest.raises(ValueError, match="Label"):
        load_any(tmp_path / "unsw.csv", fmt="cicids2017")


def test_unknown_or_missing_input_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("hello\n")
    with pytest.raises(ValueError, match="neither"):
        load_any(tmp_path / "notes.txt")
    with pytest.raises(FileNotFoundError):
        load_any(tmp_path / "absent")
    with pytest.raises(ValueError, match="unknown format"):
        load_any(tmp_path, fmt="pcap")
    (tmp_path / "UAV-CAS_ts.csv").write_text("packet_time,packet_size\n\"[1.0, 2.0]\",\"[60, 60]\"\n")
    with pytest.raises(ValueError, match="packet_dir"):
        load_any(tmp_path)
    assert set(FORMATS) == {"uavcas", "uavcas-csv", "cicids2017", "unsw-nb15"}


def test_views_are_never_mixed_silently():
    df = pd.DataFrame({"view": ["5tuple", "hostpair", "5tuple"], "x": [1, 2, 3]})
    with pytest.raises(ValueError, match="mixes.*--view"):
        select_view(df)
    assert select_view(df, "hostpair")["x"].tolist() == [2] and select_view(df, "5tuple")["x"].tolist() == [1, 3]
    with pytest.raises(ValueError, match="not in this dataset"):
        select_view(df, "other")
    with pytest.raises(ValueError, match="no 'view' column"):
        select_view(df.drop(columns="view"), "5tuple")


def test_cli_bench_reads_the_authors_csv(dataset_and_csv, tmp_path):
    _, csv = dataset_and_csv
    r = runner.invoke(app, ["bench", "ids", str(csv), "--out", str(tmp_path / "b"), "--protocol", "binary", "--models",
                            "lr"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "b" / "results.csv").exists()


@pytest.mark.shared
def test_shared_samples_are_detected_and_read(shared_data):
    cic = load_any(shared_data / "ids-samples" / "cicids2017-improved-rnd2500")
    assert cic.attrs["source"] == "cicids2017" and (cic["label"] == "Benign").sum() == 2500
    assert cic.attrs["absent_features"] == [] and cic["run_id"].is_unique
    unsw = load_any(shared_data / "ids-samples" / "unsw-nb15-testing-head4528")
    assert unsw.attrs["source"] == "unsw-nb15" and "Normal" not in set(unsw["label"])
    assert len(unsw.attrs["absent_features"]) == len(FEATURES) - 13  # 10 direct + 3 derived columns
