"""`uavcas extract | info | export | flows` on the synthetic run; shards, card, idempotency."""

from __future__ import annotations

import json
import shutil

import pyarrow.parquet as pq
from typer.testing import CliRunner

from helpers.synth_run import N_FLOOD, build_run
from uavcas.cli import app
from uavcas.dataset.parquet import COLUMNS, arrow_schema, read_flows
from uavcas.flows.standards.cic import FEATURES
from uavcas.flows.standards.paper import PAPER_FEATURES
from uavcas.schema import CLASSES, CONTEXT_FEATURES, METADATA_COLUMNS, SEQUENCE_COLUMNS

runner = CliRunner()


def _run(*args):
    return runner.invoke(app, [str(a) for a in args])


def test_extract_info_idempotent(synth_run_dir, tmp_path):
    ds = tmp_path / "ds"
    r = _run("extract", synth_run_dir, "--out", ds)
    assert r.exit_code == 0, r.output
    assert (ds / "shards" / "run-synth.parquet").exists()
    table = pq.read_table(ds / "flows.parquet")
    assert table.schema.remove_metadata() == arrow_schema(context=True)  # extraction adds the ctx_* columns
    assert set(METADATA_COLUMNS) | set(FEATURES) | set(SEQUENCE_COLUMNS) <= set(COLUMNS)
    card = json.loads((ds / "dataset.json").read_text())
    # 13 HTTP sessions, one flow each (one connection, one flow), the blackholed fetch (one flow:
    # nothing came back), the replayed copies (they join their session's flow) and the flood
    assert card["n_flows"] == table.num_rows == N_FLOOD + 13 + 1
    assert card["features"]["standard"] == "cic" and card["features"]["units"]["Flow Duration"] == "us"
    assert card["context"] == {"columns": len(CONTEXT_FEATURES), "window_s": 5.0}
    assert card["runs"][0]["flow_rules"]["idle_timeout_s"] == 15.0
    assert card["runs"][0]["flow_rules"]["termination"] == "connection" and card["terminations"] == ["connection"]
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


def test_paper_features_dataset_and_no_mixing(synth_run_dir, tmp_path):
    ds = tmp_path / "ds"
    assert _run("extract", synth_run_dir, "--out", ds, "--features", "paper").exit_code == 0
    df = read_flows(ds / "flows.parquet")
    assert df.attrs["feature_standard"] == "paper" and set(PAPER_FEATURES) <= set(df.columns)
    assert json.loads((ds / "dataset.json").read_text())["features"]["units"]["Flow Duration"] == "s"
    other = build_run(tmp_path / "run2", run_id="run-two")
    r = _run("extract", other, "--out", ds)  # a cic shard beside a paper one
    assert r.exit_code == 2 and "feature standards" in r.output


def test_every_parquet_file_reads_with_plain_pandas(synth_run_dir, tmp_path):
    import pandas as pd

    ds = tmp_path / "ds"
    assert _run("extract", synth_run_dir, "--out", ds).exit_code == 0
    assert _run("flows", synth_run_dir / "pcap" / "s-bs0.pcap", "--format", "parquet", "--out",
                tmp_path / "f.parquet").exit_code == 0
    for path in [ds / "flows.parquet", *ds.glob("shards/*.parquet"), tmp_path / "f.parquet"]:
        df = pd.read_parquet(path)
        assert len(df) > 0 and len(df.seq_size.iloc[0]) == df.packets.iloc[0], path


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
    # first_ts with nanosecond digits (a float64 %g would keep 10 s)
    row = dict(zip(header, next(__import__("csv").reader(r.output.splitlines()[1:2]))))
    assert len(row["first_ts"].split(".")[1]) == 9 and row["first_ts"].startswith("1700000")
    paper = _run("flows", pcap, "--format", "csv", "--features", "paper")
    assert paper.exit_code == 0 and paper.output.splitlines()[0].split(",")[8:8 + 47] == list(PAPER_FEATURES)
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


def test_out_never_replaces_a_symlink_fifo_or_directory(synth_run_dir, tmp_path):
    import os
    import stat

    pcap = synth_run_dir / "pcap" / "s-bs0.pcap"
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    link = tmp_path / "link.csv"
    link.symlink_to(victim)
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    folder = tmp_path / "folder"
    folder.mkdir()
    for target in (link, fifo, folder):
        for fmt in ("csv", "parquet", "table"):
            r = _run("flows", pcap, "--format", fmt, "--out", target)
            assert r.exit_code == 2 and "refusing" in r.output, (target, fmt, r.output)
    assert link.is_symlink() and os.readlink(link) == str(victim) and victim.read_text() == "precious"
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and folder.is_dir() and not any(folder.iterdir())
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary left behind
    ds = tmp_path / "ds"
    assert _run("extract", synth_run_dir, "--out", ds).exit_code == 0
    r = _run("export", ds, "--format", "uavcas-csv", "--out", fifo)
    assert r.exit_code == 2 and stat.S_ISFIFO(os.lstat(fifo).st_mode)
    out = tmp_path / "csv"
    out.mkdir()
    (out / "UAV-CAS_ts.csv").symlink_to(victim)
    r = _run("export", ds, "--format", "uavcas-csv", "--out", out)
    assert r.exit_code == 2 and (out / "UAV-CAS_ts.csv").is_symlink() and victim.read_text() == "precious"
    r = _run("extract", synth_run_dir, "--out", fifo)
    assert r.exit_code == 2 and stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_snaplen_and_orphans_are_reported_on_stderr(tmp_path):
    import struct

    from scapy.layers.inet import IP, TCP, UDP, fragment
    from scapy.layers.l2 import Ether
    from scapy.packet import Raw
    from scapy.utils import wrpcap

    pk = []
    for k in range(5):
        p = Ether() / IP(src="10.0.0.1", dst="10.0.0.2") / TCP(sport=1000 + k, dport=80, flags="S")
        p.time = 1_700_000_000 + k
        pk.append(p)
    frag = [Ether() / f
            for f in fragment(IP(src="10.0.0.1", dst="10.0.0.2", id=9) / UDP() / Raw(b"y" * 1200), fragsize=400)]
    for f in frag:
        f.time = 1_700_000_010
    wrpcap(str(tmp_path / "x.pcap"), pk + frag[1:])  # the first fragment is missing
    data = (tmp_path / "x.pcap").read_bytes()
    cut = bytearray(data[:16]) + struct.pack("<I", 40) + data[20:24]
    off = 24
    while off < len(data):
        s, f, incl, orig = struct.unpack_from("<IIII", data, off)
        keep = min(incl, 40 if off < 24 + 2 * (16 + len(pk[0])) else incl)  # the first two records cut
        cut += struct.pack("<IIII", s, f, keep, orig) + data[off + 16 : off + 16 + keep]
        off += 16 + incl
    (tmp_path / "cut.pcap").write_bytes(bytes(cut))
    r = runner.invoke(app, ["flows", str(tmp_path / "cut.pcap"), "--format", "csv"])
    assert r.exit_code == 0
    assert "2 of" in r.output and "transport header cut" in r.output and "first fragment" in r.output
