"""`uavcas.dataset.flow_files`: a stream of flow frames written as Parquet or CSV (what
`uavcas flows --format parquet|csv` writes), one frame at a time."""

from __future__ import annotations

import csv
import io
from decimal import Decimal

import pyarrow.parquet as pq
import pytest

from helpers.pcapgen import http_session, syn_flood, write
from uavcas.dataset.flow_files import csv_table, ns_decimal, write_csv, write_parquet
from uavcas.flows import CSV_LEAD_COLUMNS, FlowConfig, iter_flow_frames
from uavcas.flows.standards import feature_columns


@pytest.fixture(scope="module")
def pcap(tmp_path_factory):
    # a web session and a SYN flood: several flows, over more than one small read block
    return write(tmp_path_factory.mktemp("ff") / "a.pcap", http_session() + syn_flood(n=40) + http_session(t0=5.0))


def _frames(pcap, standard="cic", sequences=True, chunk_bytes=None):
    kw = {"chunk_bytes": chunk_bytes} if chunk_bytes else {}
    return list(iter_flow_frames([pcap], FlowConfig(), standard=standard, sequences=sequences, **kw))


def test_ns_decimal_is_exact_to_the_nanosecond_for_any_sign():
    ns = [0, 1, 1_700_000_000_123_456_789, -1, -1_500_000_000]
    assert [str(v) for v in ns_decimal(ns).to_pylist()] == [
        "0E-9", "1E-9", "1700000000.123456789", "-1E-9", "-1.500000000"]
    assert [Decimal(v) * 10**9 for v in ns_decimal(ns).to_pylist()] == ns


def test_parquet_holds_every_flow_of_every_frame_with_its_sequences(pcap, tmp_path):
    frames = _frames(pcap, chunk_bytes=2048)
    assert len(frames) > 1  # several frames reach the writer
    n = write_parquet(iter(frames), tmp_path / "f.parquet", "cic")
    t = pq.read_table(tmp_path / "f.parquet")
    assert n == t.num_rows == sum(len(f) for f in frames) > 3
    assert t.column_names == list(frames[0].columns)
    assert t.column("flow_id").to_pylist() == list(range(n))
    assert [len(s) for s in t.column("seq_size").to_pylist()] == t.column("packets").to_pylist()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary left


def test_an_empty_stream_gives_a_valid_file_with_the_flow_schema(pcap, tmp_path):
    full = tmp_path / "full.parquet"
    write_parquet(iter(_frames(pcap, standard="paper")), full, "paper")
    assert write_parquet(iter([]), tmp_path / "empty.parquet", "paper") == 0
    empty = pq.read_table(tmp_path / "empty.parquet")
    assert empty.num_rows == 0 and empty.column_names == pq.read_schema(full).names
    out = io.BytesIO()
    assert write_csv(iter([]), out, "paper") == 0
    header = out.getvalue().decode().splitlines()
    assert len(header) == 1
    assert header[0].split(",") == [*CSV_LEAD_COLUMNS, *feature_columns("paper"), "first_ts", "last_ts",
                                    "capture_point"]


@pytest.mark.parametrize("standard", ["cic", "paper"])
def test_csv_columns_and_exact_times(pcap, standard):
    frames = _frames(pcap, standard=standard, sequences=False)
    out = io.BytesIO()
    n = write_csv(iter(frames), out, standard)
    rows = list(csv.reader(out.getvalue().decode().splitlines()))
    header, body = rows[0], rows[1:]
    assert header == [*CSV_LEAD_COLUMNS, *feature_columns(standard), "first_ts", "last_ts", "capture_point"]
    assert n == len(body) == sum(len(f) for f in frames)
    first = frames[0].iloc[0]
    row = dict(zip(header, body[0]))
    assert Decimal(row["first_ts"]) * 10**9 == int(first["first_ts_ns"]) and len(row["first_ts"].split(".")[1]) == 9
    last_ns = int(first["first_ts_ns"]) + round(float(first["duration_s"]) * 1e9)
    assert Decimal(row["last_ts"]) * 10**9 == last_ns
    assert row["capture_point"] == "a" and row["src_ip"] == str(first["src_ip"])


def test_several_frames_give_the_file_of_one(pcap, tmp_path):
    """Row groups and CSV batches are an implementation detail: the bytes of the rows are the same."""
    import pandas as pd

    frames = _frames(pcap, sequences=False, chunk_bytes=2048)
    assert len(frames) > 1
    one, many = io.BytesIO(), io.BytesIO()
    write_csv(iter([pd.concat(frames, ignore_index=True)]), one, "cic")
    write_csv(iter(frames), many, "cic")
    assert one.getvalue() == many.getvalue()
    assert write_csv(iter(frames), tmp_path / "f.csv", "cic") == sum(len(f) for f in frames)
    assert (tmp_path / "f.csv").read_bytes() == many.getvalue()


def test_csv_table_quotes_only_what_needs_it(pcap):
    import pyarrow.csv as pacsv

    df = _frames(pcap, sequences=False)[0].head(1).copy()
    df["capture_point"] = "s,1"
    buf = io.BytesIO()
    pacsv.write_csv(csv_table(df, "cic"), buf, pacsv.WriteOptions(quoting_style="needed"))
    assert buf.getvalue().decode().splitlines()[1].endswith(',"s,1"')
