"""`uavcas extract | info | export | flows` on the synthetic run; shards, card, idempotency."""

from __future__ import annotations

import json
import shutil

import pyarrow.parquet as pq
from synth_run import N_FLOOD, build_run
from typer.testing import CliRunner

from uavcas.cli import app
from uavcas.dataset.parquet import COLUMNS, arrow_schema, read_flows
from uavcas.dataset.uavcas_csv import read_uavcas_csv
from uavcas.schema import CLASSES, FEATURES, METADATA_COLUMNS, SEQUENCE_COLUMNS

runner = CliRunner()


def _run(*args):
    return runner.invoke(app, [str(a) for a in args])


def test_extract_info_idempotent(synth_run_dir, tmp_path):
    ds = tmp_path / "ds"
    r = _run("extract", synth_run_dir, "--out", ds)
    assert r.exit_code == 0, r.output
    assert (ds / "shards" / "run-synth.parquet").exists()
    table = pq.read_table(ds / "flows.parquet")
    assert table.schema.remove_metadata() == arrow_schema()
    assert set(METADATA_COLUMNS) | set(FEATURES) | set(SEQUENCE_COLUMNS) <= set(COLUMNS)
    card = json.loads((ds / "dataset.json").read_text())
    assert card["n_flows"] == table.num_rows == N_FLOOD + 14
    assert card["class_counts"]["DoS"] == N_FLOOD and set(CLASSES) <= set(card["class_counts"])
    assert card["views"] == ["5tuple"] and card["seeds"] == [7] and card["runs"][0]["run_id"] == "run-synth"
    # The twin profile the run was planned with is on the card (name -> SHA-256s; None when unrecorded).
    assert card["profiles"] == {"test": []} and card["runs"][0]["profile"] == "test"
    # re-extracting replaces the shard (here with another view), never duplicates
    assert _run("extract", synth_run_dir, "--out", ds, "--view", "hostpair").exit_code == 0
    card2 = json.loads((ds / "dataset.json").read_text())
    assert card2["n_runs"] == 1 and card2["views"] == ["hostpair"] and card2["n_flows"] < card["n_flows"]
    # a second run adds a shard
    other = build_run(tmp_path / "run2", run_id="run-two")
    assert _run("extract", other, "--out", ds).exit_code == 0
    df = read_flows(ds / "flows.parquet")
    assert sorted(df.run_id.unique()) == ["run-synth", "run-two"]
    assert df.attacks.iloc[0] == "blackhole+dos=1000+replay=50,200,10,5,inc" and df.n_uav.iloc[0] == 4
    info = _run("info", ds)
    assert info.exit_code == 0 and "DoS" in info.output and "Benign" in info.output
    assert not list(ds.glob("**/*.tmp*"))


def test_export_import_roundtrip(synth_run_dir, tmp_path):
    ds, out = tmp_path / "ds", tmp_path / "csv"
    assert _run("extract", synth_run_dir, "--out", ds).exit_code == 0
    r = _run("export", ds, "--format", "uavcas-csv", "--out", out)
    assert r.exit_code == 0, r.output
    ts, stat = out / "run-synth_ts.csv", out / "run-synth_stat.csv"
    assert ts.exists() and stat.exists()
    assert ts.read_text().splitlines()[1].count("[") == 4
    back = read_uavcas_csv(ts)
    orig = read_flows(ds / "flows.parquet")
    assert len(back) == len(orig)
    assert back.label.tolist() == orig.label.tolist() and back.label_dos.tolist() == orig.label_dos.tolist()
    for a, b in zip(back.seq_size.tolist(), orig.seq_size.tolist()):
        assert list(a) == list(b)
    for a, b in zip(back.seq_time_s.tolist(), orig.seq_time_s.tolist()):
        assert max(abs(x - y) for x, y in zip(a, b)) < 2e-6
    for f in FEATURES:
        assert abs(back[f] - orig[f]).max() <= 1e-9 * max(1.0, abs(orig[f]).max()), f


def test_cli_errors_are_one_line(tmp_path, synth_run_dir):
    r = _run("extract", tmp_path / "nope", "--out", tmp_path / "ds")
    assert r.exit_code == 2 and "not a directory" in r.output
    broken = tmp_path / "broken"
    shutil.copytree(synth_run_dir, broken)
    p = broken / "pcap" / "s-bs0.pcap"
    p.write_bytes(p.read_bytes()[:-7])
    r = _run("extract", broken, "--out", tmp_path / "ds")
    assert r.exit_code == 2 and "byte offset" in r.output and "s-bs0.pcap" in r.output
    r = _run("extract", broken, "--out", tmp_path / "ds", "--allow-truncated")
    assert r.exit_code == 0 and "truncated" in r.output
    assert _run("info", tmp_path).exit_code == 2
    assert _run("extract", synth_run_dir, "--out", tmp_path / "ds", "--labels", "magic").exit_code == 2


def test_flows_command_formats(synth_run_dir, tmp_path):
    pcap = synth_run_dir / "pcap" / "s-uav0.pcap"
    r = _run("flows", pcap, "--format", "csv")
    assert r.exit_code == 0
    header = r.output.splitlines()[0].split(",")
    assert header[:8] == ["src_ip", "src_port", "dst_ip", "dst_port", "protocol", "packets", "bytes", "duration_s"]
    assert header[8 : 8 + 47] == list(FEATURES)
    assert _run("flows", pcap, "--format", "parquet", "--out", tmp_path / "f.parquet").exit_code == 0
    assert pq.read_table(tmp_path / "f.parquet").num_rows == len(r.output.splitlines()) - 1
    t = _run("flows", pcap, "--view", "hostpair", "--min-packets", "2")
    assert t.exit_code == 0 and "10.10.0.2" in t.output
    assert _run("flows", pcap, "--format", "xml").exit_code == 2
    assert _run("flows", tmp_path / "missing.pcap").exit_code == 2


def test_extract_run_id_override_names_shard_rows_and_card(synth_run_dir, tmp_path):
    from uavcas.dataset.store import extract_run

    ds = tmp_path / "ds"
    info = extract_run(synth_run_dir, ds, run_id="17")
    assert info.run_id == "17" and (ds / "shards" / "17.parquet").exists()
    assert set(read_flows(ds / "flows.parquet").run_id) == {"17"}
    assert json.loads((ds / "dataset.json").read_text())["runs"][0]["run_id"] == "17"
