"""Flow extraction throughput and dataset read speed (not part of the unit tests).

    .venv/bin/python benchmarks/flows_throughput.py [--packets 1000000] [--flows 100000]

1. Generates a >= 1 M-packet Ethernet/IPv4 capture with numpy (fixed 96-byte records: 16-byte
   record header + 80 captured bytes, wire lengths 60..1514 as with a snap length): benign TCP
   conversations of 40 packets plus an hping3-like SYN flood (new source port per packet).
2. Times, on that file: our packet reader, our full extraction (flows + sequences + 47 features),
   a naive dpkt loop (on a prefix, extrapolated), the paper's tshark-fields pipeline (tshark -T
   fields -> pandas groupby on the 5-tuple), and nfstream (pip install 'uavcas[bench]').
3. Builds a 100k-flow dataset in our schema and times reading it from Parquet vs from the
   authors' CSV layout (list literals): with our vectorised reader and with ast.literal_eval.
"""

from __future__ import annotations

import argparse
import ast
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from rich.console import Console
from rich.table import Table

from uavcas.flows import FlowConfig, assemble, extract_flows, flow_frame, read_packets

SNAP = 80
FLOW_PKTS = 40


def make_capture(path: Path, n_packets: int, seed: int = 1) -> int:
    rng = np.random.default_rng(seed)
    n_flood = n_packets // 5
    n_flows = (n_packets - n_flood) // FLOW_PKTS
    n_benign = n_flows * FLOW_PKTS
    n = n_benign + n_flood
    # benign: flow k between client 10.1.x.y:port and server 10.0.0.(k%20+1):80, alternating dirs
    fk = np.repeat(np.arange(n_flows), FLOW_PKTS)
    pos = np.tile(np.arange(FLOW_PKTS), n_flows)
    start = rng.uniform(0, 60, n_flows)
    ts_b = start[fk] + pos * rng.exponential(0.01, n_benign)
    client = (10 << 24) | (1 << 16) | (fk // 250 << 8) | (fk % 250 + 1)
    server = np.full(n_benign, (10 << 24) | 1) + fk % 20
    c2s = pos % 2 == 0
    src = np.where(c2s, client, server)
    dst = np.where(c2s, server, client)
    cport = 10000 + fk % 50000
    sport = np.where(c2s, cport, 80)
    dport = np.where(c2s, 80, cport)
    flags = np.where(pos == 0, 0x02, np.where(pos == 1, 0x12, 0x18))
    # flood: attacker 10.9.0.1 -> victim 10.0.0.1:80, new source port each packet, ~1,000 pps
    ts_f = 20 + np.arange(n_flood) * 1e-3
    src = np.concatenate([src, np.full(n_flood, (10 << 24) | (9 << 16) | 1)])
    dst = np.concatenate([dst, np.full(n_flood, (10 << 24) | 1)])
    sport = np.concatenate([sport, 1024 + np.arange(n_flood) % 60000])
    dport = np.concatenate([dport, np.full(n_flood, 80)])
    flags = np.concatenate([flags, np.full(n_flood, 0x02)])
    ts = np.concatenate([ts_b, ts_f]) + 1_700_000_000
    order = np.argsort(ts, kind="stable")
    ts, src, dst, sport, dport, flags = ts[order], src[order], dst[order], sport[order], dport[order], flags[order]
    wire = np.where(flags == 0x02, 60, rng.integers(60, 1515, n))

    rec = np.zeros((n, 16 + SNAP), dtype=np.uint8)

    def put(col: int, values: np.ndarray, width: int, big: bool = True) -> None:
        dt = (">" if big else "<") + f"u{width}"
        rec[:, col : col + width] = np.ascontiguousarray(values.astype(dt)).view(np.uint8).reshape(n, width)

    sec = np.floor(ts)
    put(0, sec, 4, big=False)
    put(4, np.round((ts - sec) * 1e6).clip(0, 999999), 4, big=False)
    put(8, np.full(n, SNAP), 4, big=False)
    put(12, wire, 4, big=False)
    e = 16
    rec[:, e : e + 12] = [2, 0, 0, 0, 0, 1, 2, 0, 0, 0, 0, 2]
    put(e + 12, np.full(n, 0x0800), 2)
    ip = e + 14
    rec[:, ip] = 0x45
    put(ip + 2, wire - 14, 2)
    put(ip + 4, np.arange(n) & 0xFFFF, 2)
    rec[:, ip + 8], rec[:, ip + 9] = 64, 6
    put(ip + 12, src, 4)
    put(ip + 16, dst, 4)
    t = ip + 20
    put(t, sport, 2)
    put(t + 2, dport, 2)
    put(t + 4, np.arange(n) * 1000, 4)
    rec[:, t + 12] = 0x50
    rec[:, t + 13] = flags
    header = np.array([0xA1B2C3D4, 0x00040002, 0, 0, 65535, 1], dtype="<u4").tobytes()
    header = header[:4] + np.array([2, 4], dtype="<u2").tobytes() + header[8:]
    with open(path, "wb") as fh:
        fh.write(header)
        fh.write(rec.tobytes())
    return n


def timed(fn):
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def bench_dpkt(path: Path, limit: int) -> tuple[float, int]:
    import dpkt

    t = time.perf_counter()
    k = 0
    with open(path, "rb") as fh:
        for ts, buf in dpkt.pcap.Reader(fh):
            eth = dpkt.ethernet.Ethernet(buf)
            ip = eth.data
            if isinstance(ip, dpkt.ip.IP) and isinstance(ip.data, dpkt.tcp.TCP):
                _ = (ts, len(buf), ip.src, ip.dst, ip.data.sport, ip.data.dport, ip.data.flags)
            k += 1
            if k >= limit:
                break
    return time.perf_counter() - t, k


def bench_tshark(path: Path) -> tuple[float, int]:
    fields = ["frame.time_epoch", "frame.len", "ip.src", "ip.dst", "tcp.srcport", "tcp.dstport", "udp.srcport", "udp.dstport", "tcp.flags"]
    cmd = ["tshark", "-n", "-r", str(path), "-T", "fields", "-E", "separator=,"] + [a for f in fields for a in ("-e", f)]

    def run():
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        df = pd.read_csv(proc.stdout, names=fields, header=None, low_memory=False)
        proc.wait()
        df["sp"] = df["tcp.srcport"].fillna(df["udp.srcport"])
        df["dp"] = df["tcp.dstport"].fillna(df["udp.dstport"])
        a = df["ip.src"].astype(str) + ":" + df["sp"].astype(str)
        b = df["ip.dst"].astype(str) + ":" + df["dp"].astype(str)
        df["key"] = np.where(a < b, a + "|" + b, b + "|" + a)
        return df.groupby("key").agg(n=("frame.len", "size"), bytes=("frame.len", "sum"), t0=("frame.time_epoch", "min"), t1=("frame.time_epoch", "max"))

    dt, flows = timed(run)
    return dt, len(flows)


def bench_nfstream(path: Path) -> tuple[float, int] | None:
    try:
        from nfstream import NFStreamer
    except ImportError:
        return None
    dt, df = timed(lambda: NFStreamer(source=str(path), n_dissections=0, statistical_analysis=True, n_meters=1).to_pandas())
    return dt, len(df)


def make_dataset(n_flows: int, seed: int = 2) -> pd.DataFrame:
    """A 100k-flow frame in our schema from a synthetic capture of ~n_flows conversations."""
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "ds.pcap"
        make_capture(p, int(n_flows * FLOW_PKTS / 0.8 * 0.8) + n_flows // 4, seed)
        ex = extract_flows([p])
    df = ex.frame.head(n_flows).copy()
    df["label"] = np.where(df.src_ip == "10.9.0.1", "DoS", "Benign")
    df["config"] = "benign-5-2-image-logdist-adaptive-random-30-95"
    return df


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--packets", type=int, default=1_000_000)
    ap.add_argument("--flows", type=int, default=100_000)
    ap.add_argument("--dpkt-packets", type=int, default=200_000, help="dpkt is timed on this prefix")
    ap.add_argument("--workdir", type=Path, default=None)
    args = ap.parse_args()
    work = args.workdir or Path(tempfile.mkdtemp(prefix="uavcas-bench-"))
    work.mkdir(parents=True, exist_ok=True)
    con = Console()
    rows: list[tuple[str, str, str, str]] = []
    cap = work / "bench.pcap"
    dt, n = timed(lambda: make_capture(cap, args.packets))
    con.print(f"capture: {n:,} packets, {cap.stat().st_size / 1e6:.0f} MB, generated in {dt:.1f} s")

    dt, pk = timed(lambda: read_packets([cap]))
    rows.append(("uavcas read_packets (pcap -> columns)", f"{dt:.2f}", f"{n / dt:,.0f}", f"{len(pk):,} packets"))
    dt2, fl = timed(lambda: assemble(pk, FlowConfig()))
    dt3, fr = timed(lambda: flow_frame(pk, fl))
    tot = dt + dt2 + dt3
    rows.append(("uavcas extraction (read+flows+sequences+47 features)", f"{tot:.2f}", f"{n / tot:,.0f}", f"{len(fr):,} flows"))
    dt, k = bench_dpkt(cap, args.dpkt_packets)
    rows.append((f"dpkt naive loop (first {k:,} packets)", f"{dt * n / k:.2f}*", f"{k / dt:,.0f}", "decode only, extrapolated"))
    if shutil.which("tshark"):
        dt, nf = bench_tshark(cap)
        rows.append(("paper pipeline: tshark -T fields | pandas groupby", f"{dt:.2f}", f"{n / dt:,.0f}", f"{nf:,} flows"))
    nfs = bench_nfstream(cap)
    if nfs is not None:
        rows.append(("nfstream (statistical_analysis, no dissection)", f"{nfs[0]:.2f}", f"{n / nfs[0]:,.0f}", f"{nfs[1]:,} flows"))
    table = Table(title=f"Flow extraction on {n:,} packets")
    for c in ("tool", "seconds", "packets/s", "note"):
        table.add_column(c, justify="left" if c in ("tool", "note") else "right")
    for r in rows:
        table.add_row(*r)
    con.print(table)

    from uavcas.dataset.uavcas_csv import read_uavcas_csv, write_uavcas_csv
    import pyarrow as pa
    import pyarrow.parquet as pq

    df = make_dataset(args.flows)
    pq_path = work / "flows.parquet"
    pq.write_table(pa.Table.from_pandas(df, preserve_index=False), pq_path, compression="zstd")
    write_uavcas_csv(df, work, "bench")
    ts_csv = work / "bench_ts.csv"
    from uavcas.dataset.parquet import read_flows

    t2 = Table(title=f"Reading a {len(df):,}-flow dataset")
    for c in ("format / reader", "seconds", "MB on disk"):
        t2.add_column(c, justify="left" if c.startswith("format") else "right")
    dt, _ = timed(lambda: read_flows(pq_path))
    t2.add_row("Parquet (list columns), uavcas read_flows", f"{dt:.2f}", f"{pq_path.stat().st_size / 1e6:.1f}")
    csv_mb = (ts_csv.stat().st_size + (work / "bench_stat.csv").stat().st_size) / 1e6
    dt, _ = timed(lambda: read_uavcas_csv(ts_csv))
    t2.add_row("authors' CSV (_ts + _stat), uavcas vectorised reader", f"{dt:.2f}", f"{csv_mb:.1f}")

    def literal():
        d = pd.read_csv(ts_csv)
        for c in ("timestamps", "sizes", "flags", "directions"):
            d[c] = d[c].map(ast.literal_eval)
        return pd.read_csv(work / "bench_stat.csv"), d

    dt, _ = timed(literal)
    t2.add_row("authors' CSV, pandas + ast.literal_eval", f"{dt:.2f}", f"{csv_mb:.1f}")
    con.print(t2)
    if args.workdir is None:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
