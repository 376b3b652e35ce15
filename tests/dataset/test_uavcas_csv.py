"""The authors' released layout both ways: columns and conventions by hand, multi-run export,
export -> import -> export byte-identical, their files as released."""

from __future__ import annotations

import ast
import csv

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest
from typer.testing import CliRunner

from helpers.synth_run import build_run
from uavcas.cli import app
from uavcas.dataset.parquet import read_flows
from uavcas.dataset.uavcas_csv import STAT_COLUMNS, read_layout, write_layout
from uavcas.flows.standards.paper import PAPER_FEATURES
from uavcas.schema import FAMILIES

runner = CliRunner()
T = 1_795_558_508_949_186_000  # ns


def _run(*args):
    return runner.invoke(app, [str(a) for a in args])


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def _lists(values, starts, typ):
    return pd.arrays.ArrowExtensionArray(pa.ListArray.from_arrays(pa.array(np.asarray(starts, dtype=np.int32)),
                                                                  pa.array(values, type=typ)))


def _tiny_dataset():
    """Three flows of run '4': 12 packets (stat + ts), 3 packets (ts only), 1 packet (neither)."""
    rel = [np.arange(12) * 0.0105, np.array([0.0, 0.25, 1.5]), np.array([0.0])]
    sizes = [np.array([74, 74, 66, 149] + [1514] * 6 + [66, 66]), np.array([60, 120, 60]), np.array([60])]
    flags = [np.array([2, 0x12, 0x10, 0x18] + [0x10] * 6 + [0x11, 0x10]), np.zeros(3, int), np.array([2])]
    dirs = [np.array([1, -1, 1, 1, -1, -1, -1, -1, -1, -1, 1, -1]), np.array([1, -1, 1]), np.array([1])]
    starts = np.concatenate(([0], np.cumsum([len(r) for r in rel])))
    n = 3
    df = pd.DataFrame({
        "run_id": ["4"] * n, "config": ["dos=1000-5-2-image-logdist-adaptive-spiral-30-95"] * n, "seed": [1] * n,
        "view": ["5tuple"] * n, "flow_id": range(n),
        # '10.0.0.2' sends first (forward) but '10.0.0.10' is the string-smaller address
        "src_ip": ["10.0.0.2", "10.0.0.3", "10.0.0.3"], "src_port": [40000, 53, 9],
        "dst_ip": ["10.0.0.10", "10.0.0.4", "10.0.0.4"],
        "dst_port": [80, 4000, 9], "protocol": [6, 17, 6], "first_ts_ns": [T, T + 5 * 10**9, T + 9 * 10**9],
        "attacks": ["dos=1000"] * n, "n_uav": [5] * n, "n_bs": [2] * n, "payload": ["image"] * n,
        "pathloss": ["logdist"] * n, "modulation": ["adaptive"] * n, "mission": ["spiral"] * n, "tx_dbm": [30] * n,
        "noise_dbm": [-95.0] * n, "packets": [12, 3, 1], "label": ["DoS", "Benign", "Benign"],
    })  # fmt: skip
    df["first_ts"] = df["first_ts_ns"] / 1e9
    df["seq_time_s"] = _lists(np.concatenate(rel), starts, pa.float64())
    df["seq_size"] = _lists(np.concatenate(sizes).astype(np.int32), starts, pa.int32())
    df["seq_flags"] = _lists(np.concatenate(flags).astype(np.int16), starts, pa.int16())
    df["seq_dir"] = _lists(np.concatenate(dirs).astype(np.int8), starts, pa.int8())
    df.attrs["feature_standard"] = "cic"
    return df, rel, sizes, flags, dirs


def test_columns_and_conventions_by_hand(tmp_path):
    df, rel, sizes, flags, dirs = _tiny_dataset()
    w = write_layout(df, tmp_path)
    assert (w.stat.name, w.ts.name, w.n_stat, w.n_ts) == ("UAV-CAS_stat.csv", "UAV-CAS_ts.csv", 1, 2)
    assert w.stat.read_bytes().count(b"\r\n") == 2  # csv.writer's CRLF, as their files
    stat, ts = _rows(w.stat), _rows(w.ts)
    assert stat[0] == list(STAT_COLUMNS) and len(stat[0]) == 59
    assert stat[0][:11] == ["config_idx", "num_drones", "num_bs", "payload", "pathloss", "modulation", "mission",
                            "tx_power", "noise", "src_ip", "dst_ip"] and stat[0][-1] == "Label"  # fmt: skip
    assert ts[0] == ["packet_time", "packet_size", "packet_dir", "Label"]
    # ts: the flows of >= 2 packets, Python literals, exact times, direction 0 = string-smaller sender
    times = ast.literal_eval(ts[1][0])
    assert times == [(T + round(x * 1e9)) / 10**9 for x in rel[0]] and ts[1][0].startswith("[1795558508.949186, ")
    assert ast.literal_eval(ts[1][1]) == sizes[0].tolist()
    assert ast.literal_eval(ts[1][2]) == [0 if d == -1 else 1 for d in dirs[0]]  # 10.0.0.10 sends the -1s
    assert ast.literal_eval(ts[2][2]) == [0, 1, 0] and ts[2][3] == "Benign" and ts[1][3] == "DoS"
    # stat: meta strings as their config parts, the pair in string order, features by their formulas
    r = dict(zip(stat[0], stat[1]))
    assert [r[c] for c in STAT_COLUMNS[:11]] == ["4", "5", "2", "image", "logdist", "adaptive", "spiral", "30", "95",
                                                 "10.0.0.10", "10.0.0.2"]  # fmt: skip
    t = np.array([(T + round(x * 1e9)) / 10**9 for x in rel[0]])
    s, d0 = sizes[0], dirs[0] == -1
    dur, iat = t[-1] - t[0], np.diff(t)
    expect = {
        "Flow Duration": repr(dur), "Total Packets": "12", "Total Length of Packets": str(s.sum()),
        "Flow Bytes/s": repr(s.sum() / dur), "Flow Packets/s": repr(12 / dur), "Flow IAT Total": repr(iat.sum()),
        "Flow IAT Std": repr(iat.std()), "Min Packet Length": "66", "Max Packet Length": "1514",
        "Packet Length Std": repr(s.std()), "Packet Length Variance": repr(s.var()), "FIN Flag Count": "1",
        "SYN Flag Count": "2", "ACK Flag Count": "11", "PSH Flag Count": "1", "Header Length": "240",
        "Total Fwd Packets": str(d0.sum()), "Total Bwd Packets": str((~d0).sum()),
        "Total Length of Fwd Packets": str(s[d0].sum()), "Fwd Packet Length Max": "1514.0",
        "Fwd Packet Length Std": repr(s[d0].std()), "Bwd Packet Length Mean": repr(s[~d0].mean()),
        "Fwd IAT Total": repr(np.diff(t[d0]).sum()), "Bwd IAT Std": repr(np.diff(t[~d0]).std()),
        "Fwd Header Length": str(20 * d0.sum()), "Label": "DoS",
    }  # fmt: skip
    for k, v in expect.items():
        if k in ("Flow Duration", "Flow Bytes/s", "Flow Packets/s", "Flow IAT Total", "Flow IAT Std",
                 "Packet Length Std",
                 "Packet Length Variance", "Fwd Packet Length Std", "Bwd Packet Length Mean", "Fwd IAT Total",
                 "Bwd IAT Std"):
            assert float(r[k]) == pytest.approx(float(v.removeprefix("np.float64(").rstrip(")")), rel=1e-12), k
        else:
            assert r[k] == v, k
    # --embed-config and --include-flags: the _cfg variants and tshark's flag strings
    w2 = write_layout(df, tmp_path / "cfg", embed_config=True, include_flags=True)
    assert (w2.stat.name, w2.ts.name) == ("UAV-CAS_stat_cfg.csv", "UAV-CAS_ts_cfg.csv")
    ts2 = _rows(w2.ts)
    assert ts2[0] == ["packet_time", "packet_size", "packet_flag", "packet_dir", "Label"]
    assert ast.literal_eval(ts2[1][2])[:2] == ["0x0002", "0x0012"] and ast.literal_eval(ts2[2][2]) == ["", "", ""]
    assert ts2[1][4] == "DoS|dos=1000-5-2-image-logdist-adaptive-spiral-30-95"
    assert _rows(w2.stat)[1][-1] == ts2[1][4]


@pytest.fixture(scope="module")
def three_runs(synth_run_dir, tmp_path_factory):
    root = tmp_path_factory.mktemp("layout")
    ds = root / "ds"
    for run in (synth_run_dir, build_run(root / "r2", run_id="7"), build_run(root / "r3", run_id="8")):
        assert _run("extract", run, "--out", ds).exit_code == 0
    return ds


def test_every_runs_sequences_are_exported_unshifted(three_runs, tmp_path):
    df = read_flows(three_runs / "flows.parquet")
    assert df.run_id.nunique() == 3
    # a sliced frame (Arrow list offsets not starting at 0): the defect that emptied runs 2..n
    part = df.iloc[5:].reset_index(drop=True)
    part.attrs["feature_standard"] = "cic"
    w = write_layout(part, tmp_path)
    ts = _rows(w.ts)[1:]
    keep = part[part.packets >= 2].reset_index(drop=True)
    assert len(ts) == len(keep) and set(keep.run_id) == set(df.run_id)
    for row, (_, f) in zip(ts, keep.iterrows()):
        times = ast.literal_eval(row[0])
        want = [(int(f.first_ts_ns) + round(x * 1e9)) / 10**9 for x in f.seq_time_s]
        assert times == want and ast.literal_eval(row[1]) == list(f.seq_size) and row[-1] == f.label


def test_export_import_export_is_byte_identical(three_runs, tmp_path):
    for extra in ([], ["--embed-config", "--include-flags"]):
        a, ds2, b = tmp_path / f"a{len(extra)}", tmp_path / f"ds{len(extra)}", tmp_path / f"b{len(extra)}"
        r = _run("export", three_runs, "--format", "uavcas-csv", "--out", a, *extra)
        assert r.exit_code == 0, r.output
        r = _run("import", a, "--format", "uavcas-csv", "--out", ds2)
        assert r.exit_code == 0 and "lacks" in r.output and "src_port" in r.output, r.output
        assert _run("export", ds2, "--format", "uavcas-csv", "--out", b, *extra).exit_code == 0
        names = sorted(p.name for p in a.iterdir())
        assert names == sorted(p.name for p in b.iterdir()) and len(names) == 2
        for name in names:
            assert (a / name).read_bytes() == (b / name).read_bytes(), name
        imported = pd.read_parquet(ds2 / "flows.parquet")  # plain pandas reads what import writes
        assert set(imported.run_id) >= {"7", "8"} and set(PAPER_FEATURES) <= set(imported.columns)
    assert _run("import", a, "--format", "uavcas-csv", "--out", ds2).exit_code == 2  # never over a dataset


def _their_files(d):
    """Two rows as the authors' scripts write them (csv.writer; their float/int/list formatting)."""
    d.mkdir()
    t = [1700000001.000005, 1700000001.25, 1700000002.5] + [1700000003.0 + 0.125 * k for k in range(9)]
    sizes = [60] * 12
    dirs = [0, 1] * 6
    feats = {f: 0.0 for f in PAPER_FEATURES}
    feats.update({"Total Packets": 12, "Total Length of Packets": 720, "Min Packet Length": 60, "Max Packet Length": 60,
                  "Header Length": 240, "Total Fwd Packets": 6, "Total Bwd Packets": 6,
                  "Total Length of Fwd Packets": 360,
                  "Total Length of Bwd Packets": 360, "Fwd Header Length": 120, "Bwd Header Length": 120,
                  **{k: 0 for k in PAPER_FEATURES if "Flag" in k}, "Flow Duration": t[-1] - t[0]})  # fmt: skip
    with open(d / "UAV-CAS_ts_cfg.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["packet_time", "packet_size", "packet_flag", "packet_dir", "Label"])
        w.writerow(["[" + ", ".join(repr(x) for x in t) + "]", str(sizes), str(["0x0010"] * 12), str(dirs),
                    "Blackhole+DoS|blackhole+dos=1000-6-2-image-3gpp-adaptive-random-10-95"])  # fmt: skip
        w.writerow(["[1700000009.5, 1700000009.75]", "[60, 60]", "['', '']", "[0, 0]",
                    "Benign|blackhole+dos=1000-6-2-image-3gpp-adaptive-random-10-95"])
    with open(d / "UAV-CAS_stat_cfg.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(list(STAT_COLUMNS))
        w.writerow([3, "6", "2", "image", "3gpp", "adaptive", "random", "10", "95", "10.0.0.1", "10.0.0.5"]
                   + [feats[f] for f in PAPER_FEATURES]
                   + ["Blackhole+DoS|blackhole+dos=1000-6-2-image-3gpp-adaptive-random-10-95"])  # fmt: skip
    return d


def test_their_files_as_released(tmp_path):
    src = _their_files(tmp_path / "theirs")
    imp = read_layout(src)
    df = imp.frame
    assert len(df) == 2 and df.attrs["feature_standard"] == "paper"
    r = df.iloc[0]
    assert (r.run_id, r.src_ip, r.dst_ip, r.n_uav, r.tx_dbm, r.noise_dbm,
            r.pathloss) == ("3", "10.0.0.1", "10.0.0.5", 6, 10, -95.0, "3gpp")
    assert r.label == "Blackhole+DoS" and r.label_blackhole and r.label_dos and not r.label_replay
    assert r.config == "blackhole+dos=1000-6-2-image-3gpp-adaptive-random-10-95" and r.attacks == "blackhole+dos=1000"
    assert r.first_ts_ns == 1700000001_000005000 and list(r.seq_dir)[:2] == [1, -1] and list(r.seq_flags)[0] == 0x10
    assert df.iloc[1].run_id == "unknown" and np.isnan(df.iloc[1]["Total Packets"])  # a ts row alone: no index
    assert {"src_port", "protocol"} <= set(imp.lacks) and set(FAMILIES)
    out = tmp_path / "ds"
    assert _run("import", src, "--format", "uavcas-csv", "--out", out).exit_code == 0
    back = tmp_path / "back"
    assert _run("export", out, "--format", "uavcas-csv", "--out", back, "--embed-config",
                "--include-flags").exit_code == 0
    for name in ("UAV-CAS_stat_cfg.csv", "UAV-CAS_ts_cfg.csv"):
        assert (back / name).read_bytes() == (src / name).read_bytes(), name


def test_misaligned_files_are_refused(tmp_path):
    src = _their_files(tmp_path / "theirs")
    rows = _rows(src / "UAV-CAS_ts_cfg.csv")
    with open(src / "UAV-CAS_ts_cfg.csv", "w", newline="") as fh:
        csv.writer(fh).writerows([rows[0], rows[2]])  # the 12-packet row is gone
    r = _run("import", src, "--format", "uavcas-csv", "--out", tmp_path / "ds")
    assert r.exit_code == 2 and "not the ts rows" in r.output and not (tmp_path / "ds" / "flows.parquet").exists()
    (tmp_path / "empty").mkdir()
    r = _run("import", tmp_path / "empty", "--out", tmp_path / "ds2")
    assert r.exit_code == 2 and "UAV-CAS_stat.csv" in r.output
