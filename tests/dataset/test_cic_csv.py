"""`uavcas export --format csv`: one row per flow with CICIDS2017's names, Label last, no sequences,
NaN / Infinity written as CICIDS2017's CSVs hold them; read back by our CICIDS2017 loader and by
pandas; episodes and uavcas-csv-only options refused in one line."""

from __future__ import annotations

import csv

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from uavcas.cli import app
from uavcas.dataset.external import load_cicids2017
from uavcas.dataset.parquet import read_flows
from uavcas.dataset.read import detect_format
from uavcas.dataset.store import extract_run
from uavcas.dataset.synthetic import make_flows, write_dataset
from uavcas.flows.standards.cic import FEATURES
from uavcas.schema import SEQUENCE_COLUMNS

runner = CliRunner()
HEAD = ["Flow ID", "Source IP", "Source Port", "Destination IP", "Destination Port", "Protocol", "Timestamp"]


def _run(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def ds(synth_run_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("csv") / "ds"
    extract_run(synth_run_dir, out)
    return out


@pytest.fixture(scope="module")
def exported(ds, tmp_path_factory):
    out = tmp_path_factory.mktemp("csvout") / "flows.csv"
    r = _run("export", ds, "--format", "csv", "--out", out)
    assert r.exit_code == 0, r.output
    return out


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def test_columns_are_cicids2017s_with_the_label_last(ds, exported):
    header, *rows = _rows(exported)
    df = read_flows(ds / "flows.parquet")
    assert header[:7] == HEAD and header[7:54] == list(FEATURES) and header[-1] == "Label"
    assert not set(SEQUENCE_COLUMNS) & set(header) and "first_ts" not in header and "label" not in header
    assert {"run_id", "first_ts_ns", "attack_fraction", "label_dos"} <= set(header)
    assert len(rows) == len(df) and all(len(r) == len(header) for r in rows)
    first = dict(zip(header, rows[0]))
    f0 = df.iloc[0]
    assert first["Flow ID"] == f"{f0.src_ip}-{f0.dst_ip}-{f0.src_port}-{f0.dst_port}-{f0.protocol}"
    ts = pd.Timestamp(first["Timestamp"])
    assert ts.tz is not None and ts.value // 1000 == int(f0.first_ts_ns) // 1000
    assert [r[-1] for r in rows] == df["label"].tolist()


def test_nan_and_infinity_are_written_as_cicids2017_writes_them(ds, exported):
    header, *rows = _rows(exported)
    df = read_flows(ds / "flows.parquet")
    zero = np.flatnonzero((df["Flow Duration"] == 0).to_numpy())
    assert zero.size  # the SYN flood's unanswered SYNs: one packet, no payload
    bps, pps, iat = header.index("Flow Bytes/s"), header.index("Flow Packets/s"), header.index("Flow IAT Mean")
    for i in zero:
        assert rows[i][bps] == "NaN" and rows[i][pps] == "Infinity" and rows[i][iat] == "NaN", rows[i][:12]
    text = exported.read_text()
    assert "inf," not in text and ",nan" not in text
    # read back: pandas and our CICIDS2017 loader give the same numbers, NaN and inf included
    assert detect_format(exported) == "cicids2017"
    back = load_cicids2017(exported)
    for f in FEATURES:
        np.testing.assert_array_equal(back[f].to_numpy(), df[f].to_numpy(), err_msg=f)
    assert (back["label"] == df["label"]).all() and (back["src_port"] == df["src_port"]).all()


def test_strings_with_commas_are_quoted_and_read_back(tmp_path):
    df = make_flows(3, flows_per_run=4, seed=2)
    df.loc[df.index[0], "config"] = 'replay=5,100,"odd"'  # a comma and quotes in one field
    ds = write_dataset(tmp_path / "ds", df)
    r = _run("export", ds, "--format", "csv", "--out", tmp_path / "f.csv")
    assert r.exit_code == 0, r.output
    back = pd.read_csv(tmp_path / "f.csv")
    assert back["config"].tolist() == read_flows(ds / "flows.parquet")["config"].tolist()
    assert len(back) == len(df) and back.columns[-1] == "Label"


def test_episodes_and_layout_options_are_refused_in_one_line(synth_run_dir, tmp_path):
    ep = tmp_path / "ep"
    extract_run(synth_run_dir, ep, view="window-host")
    for argv, needle in (
        (["export", ep, "--format", "csv", "--out", tmp_path / "e.csv"], "--view 5tuple"),
        (["export", ep, "--format", "csv", "--out", tmp_path / "e.csv", "--embed-config"], "uavcas-csv only"),
        (["export", ep, "--format", "csv", "--out", tmp_path / "no" / "e.csv"], "does not exist"),
        (["import", tmp_path, "--format", "csv", "--out", tmp_path / "i"], "'csv' is not one of"),
    ):
        r = _run(*argv)
        assert r.exit_code == 2 and r.output.startswith("error: ") and r.output.count("\n") == 1, r.output
        assert needle in r.output, r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ep"]
