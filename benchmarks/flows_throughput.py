"""Flow extraction: wall time and peak memory, ours vs nfstream side by side (not a unit test).

    .venv/bin/pip install -e '.[bench]'            # nfstream, only for the comparison
    .venv/bin/python benchmarks/flows_throughput.py --campaign /tmp/quick [--repeat 3]
    .venv/bin/python benchmarks/flows_throughput.py --pcap BIG.pcap [--repeat 3]
    .venv/bin/python benchmarks/flows_throughput.py --packets 1000000      # synthetic capture

1. The capture: `--pcap FILE`; or `--campaign DIR` merges every capture of a campaign's runs
   (`DIR/runs/*/pcap/*.pcap`, mergecap) and appends time-shifted copies (editcap -t) until it holds
   at least `--min-packets` (1,000,000); or a synthetic Ethernet/IPv4 capture made with numpy.
2. Each tool runs in its own process, alternately, `--repeat` times; the table gives the fastest
   wall time and the largest peak RSS (`wait4` rusage of the child): `uavcas flows FILE --format csv`
   (streamed: blocks of 32 MB, flows carried across them, cic features) and nfstream writing CSV
   (`NFStreamer(n_dissections=0, statistical_analysis=True, n_meters=1).to_csv`).
3. Growth: our peak RSS on prefixes of 1/8, 1/4, 1/2 and all of the capture (sub-linear = the
   ratio to the smallest prefix grows slower than the packet count).
4. Reading a dataset: Parquet (list columns) vs the authors' CSV layout.
"""

from __future__ import annotations

import argparse
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

SNAP = 80
FLOW_PKTS = 40
NFSTREAM = ("from nfstream import NFStreamer; import sys; "
            "NFStreamer(source=sys.argv[1], n_dissections=0, statistical_analysis=True, n_meters=1)"
            ".to_csv(sys.argv[2])")


def make_capture(path: Path, n_packets: int, seed: int = 1) -> int:
    """Benign TCP conversations of 40 packets plus an hping3-like SYN flood, 80 captured bytes."""
    rng = np.random.default_rng(seed)
    n_flood = n_packets // 5
    n_flows = (n_packets - n_flood) // FLOW_PKTS
    n_benign = n_flows * FLOW_PKTS
    n = n_benign + n_flood
    fk = np.repeat(np.arange(n_flows), FLOW_PKTS)
    pos = np.tile(np.arange(FLOW_PKTS), n_flows)
    start = rng.uniform(0, 60, n_flows)
    ts_b = start[fk] + pos * rng.exponential(0.01, n_benign)
    client = (10 << 24) | (1 << 16) | (fk // 250 << 8) | (fk % 250 + 1)
    server = np.full(n_benign, (10 << 24) | 1) + fk % 20
    c2s = pos % 2 == 0
    src, dst = np.where(c2s, client, server), np.where(c2s, server, client)
    cport = 10000 + fk % 50000
    sport, dport = np.where(c2s, cport, 80), np.where(c2s, 80, cport)
    flags = np.where(pos == 0, 0x02, np.where(pos == 1, 0x12, 0x18))
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
    header = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)
    with open(path, "wb") as fh:
        fh.write(header)
        fh.write(rec.tobytes())
    return n


def count_packets(path: Path) -> int:
    from uavcas.flows.pcapio import iter_capture

    return sum(raw.n for raw in iter_capture(path))


def merge_campaign(campaign: Path, out: Path, min_packets: int) -> int:
    """All captures of a campaign's runs in one file, plus time-shifted copies up to min_packets."""
    pcaps = sorted(str(p) for p in campaign.glob("runs/*/pcap/*.pcap"))
    if not pcaps or not shutil.which("mergecap") or not shutil.which("editcap"):
        sys.exit(f"{campaign}: no runs/*/pcap/*.pcap, or mergecap/editcap missing")
    base = out.with_suffix(".base.pcap")
    subprocess.run(["mergecap", "-F", "pcap", "-w", str(base), *pcaps], check=True)
    n = count_packets(base)
    parts, k = [str(base)], 1
    while n * len(parts) < min_packets:
        shifted = out.with_suffix(f".shift{k}.pcap")
        subprocess.run(["editcap", "-F", "pcap", "-t", str(86400 * k), str(base), str(shifted)], check=True)
        parts.append(str(shifted))
        k += 1
    subprocess.run(["mergecap", "-F", "pcap", "-a", "-w", str(out), *parts], check=True)
    for p in parts:
        Path(p).unlink()
    return n * len(parts)


def prefix(path: Path, out: Path, n_records: int) -> None:
    """The first n_records packets of a pcap (record framing copied as it is)."""
    data = path.open("rb")
    head = data.read(24)
    with open(out, "wb") as fh:
        fh.write(head)
        for _ in range(n_records):
            rh = data.read(16)
            if len(rh) < 16:
                break
            fh.write(rh + data.read(struct.unpack("<I", rh[8:12])[0]))
    data.close()


def measure(cmd: list[str]) -> tuple[float, float]:
    """(wall s, peak RSS MB) of one child process."""
    t = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"failed: {' '.join(cmd)}")
    return wall, usage.ru_maxrss / 1024.0


def ours_cmd(pcap: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "uavcas.cli", "flows", str(pcap), "--format", "csv", "--out", str(out)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pcap", type=Path)
    ap.add_argument("--campaign", type=Path, help="a campaign dataset directory (its runs/*/pcap are merged)")
    ap.add_argument("--min-packets", type=int, default=1_000_000)
    ap.add_argument("--packets", type=int, default=1_000_000, help="synthetic capture size (no --pcap/--campaign)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--flows", type=int, default=0, help="also time reading a dataset of this many flows")
    ap.add_argument("--workdir", type=Path, default=None)
    args = ap.parse_args()
    work = args.workdir or Path(tempfile.mkdtemp(prefix="uavcas-bench-"))
    work.mkdir(parents=True, exist_ok=True)
    con = Console()
    if args.pcap:
        cap = args.pcap
        n = count_packets(cap)
    elif args.campaign:
        cap = work / "campaign.pcap"
        n = merge_campaign(args.campaign, cap, args.min_packets)
    else:
        cap = work / "synthetic.pcap"
        n = make_capture(cap, args.packets)
    con.print(f"capture: {cap} ({n:,} packets, {cap.stat().st_size / 1e6:.0f} MB)")

    try:
        import nfstream  # noqa: F401

        have_nfs = True
    except ImportError:
        have_nfs = False
        con.print("[yellow]nfstream is not installed (pip install -e '.[bench]'): ours only[/]")
    runs: dict[str, list[tuple[float, float]]] = {"uavcas": [], "nfstream": []}
    for _ in range(args.repeat):
        runs["uavcas"].append(measure(ours_cmd(cap, work / "ours.csv")))
        if have_nfs:
            runs["nfstream"].append(measure([sys.executable, "-c", NFSTREAM, str(cap), str(work / "nfs.csv")]))
    table = Table(title=f"Flow extraction of {n:,} packets ({args.repeat} runs each, alternating)")
    for c in ("tool", "best wall s", "packets/s", "peak RSS MB"):
        table.add_column(c, justify="left" if c == "tool" else "right")
    names = {"uavcas": "uavcas flows --format csv (streamed, cic)",
             "nfstream": "nfstream 6 (statistical, no DPI, 1 meter)"}
    for tool, res in runs.items():
        if res:
            wall, rss = min(r[0] for r in res), max(r[1] for r in res)
            table.add_row(names[tool], f"{wall:.2f}", f"{n / wall:,.0f}", f"{rss:.0f}")
    con.print(table)

    growth = Table(title="uavcas peak RSS vs capture size (prefixes)")
    for c in ("packets", "peak RSS MB", "x packets", "x RSS"):
        growth.add_column(c, justify="right")
    base = None
    for frac in (8, 4, 2, 1):
        k = n // frac
        p = cap if frac == 1 else work / f"prefix{frac}.pcap"
        if frac != 1:
            prefix(cap, p, k)
        rss = max(measure(ours_cmd(p, work / "p.csv"))[1] for _ in range(max(1, args.repeat - 1)))
        base = base or (k, rss)
        growth.add_row(f"{k:,}", f"{rss:.0f}", f"{k / base[0]:.1f}", f"{rss / base[1]:.2f}")
    con.print(growth)
    if args.flows:
        read_bench(con, work, args.flows)
    if args.workdir is None:
        shutil.rmtree(work, ignore_errors=True)


def read_bench(con: Console, work: Path, n_flows: int) -> None:
    """Reading a dataset: Parquet vs the authors' layout (our reader, and ast.literal_eval)."""
    import ast

    import pandas as pd

    from uavcas.analysis.synthetic import make_flows, write_dataset
    from uavcas.dataset.parquet import read_flows
    from uavcas.dataset.uavcas_csv import read_layout, write_layout

    ds = write_dataset(work / "ds", make_flows(n_flows, flows_per_run=200))
    df = read_flows(ds / "flows.parquet")
    write_layout(df, work / "csv")
    t2 = Table(title=f"Reading a {len(df):,}-flow dataset")
    for c in ("format / reader", "seconds", "MB on disk"):
        t2.add_column(c, justify="left" if c.startswith("format") else "right")
    t = time.perf_counter()
    read_flows(ds / "flows.parquet")
    t2.add_row("Parquet (list columns), uavcas read_flows", f"{time.perf_counter() - t:.2f}",
               f"{(ds / 'flows.parquet').stat().st_size / 1e6:.1f}")
    mb = sum(p.stat().st_size for p in (work / "csv").iterdir()) / 1e6
    t = time.perf_counter()
    read_layout(work / "csv")
    t2.add_row("authors' CSV (stat + ts), uavcas read_layout", f"{time.perf_counter() - t:.2f}", f"{mb:.1f}")
    t = time.perf_counter()
    d = pd.read_csv(work / "csv" / "UAV-CAS_ts.csv")
    for c in ("packet_time", "packet_size", "packet_dir"):
        d[c] = d[c].map(ast.literal_eval)
    pd.read_csv(work / "csv" / "UAV-CAS_stat.csv")
    t2.add_row("authors' CSV, pandas + ast.literal_eval", f"{time.perf_counter() - t:.2f}", f"{mb:.1f}")
    con.print(t2)


if __name__ == "__main__":
    main()
