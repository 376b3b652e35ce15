"""Sizing: what one run costs per swarm size, and how many hosts the paper preset needs in a night.

    sudo .venv/bin/python benchmarks/sizing.py [--sizes 5,10,20,50,100] [--windows 4] [--seed 7]
        [--out /tmp/sizing] [--json FILE]

Per size, one real run `uavcas run ddos=1000-N-B-image-logdist-adaptive-random-30-95` (B = 2 base
stations up to 20 UAVs, 4 above, as issue 28's 100-UAV case), one after the other, nothing else of
ours running. Measured:
- wall time of the whole `uavcas run` (set-up, schedule, stop, audit);
- peak memory: the largest rise of the host's used memory (MemTotal - MemAvailable, sampled every
  0.2 s) over its value before the run: namespaces, captures in page cache and every process;
- CPU: user + system seconds of the run's process tree (`RUSAGE_CHILDREN`: every process the run
  started and reaped), and that over the wall time (cores busy on average);
- capture size per minute of schedule (all switch pcaps);
- the fidelity audit: verdict, per-hop delay error p99, window change max, and which checks failed.

The night estimate: the paper preset is 1,024 runs of 12 windows x 5 s at 5, 10, 15 and 20 UAVs
(256 each). A run's wall time is taken as its measured overhead (wall - windows x window_s) plus
the preset's 60 s of schedule; 15 UAVs uses the mean of 10 and 20. One run at a time per 2-core
host (two at once break the audit's tolerances here); hosts = ceil(total / night).
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import threading
import time
from pathlib import Path

UAVCAS = [sys.executable, "-m", "uavcas.cli"]
CONFIG = "ddos=1000-{n}-{bs}-image-logdist-adaptive-random-30-95"
PAPER_SIZES = {5: 256, 10: 256, 15: 256, 20: 256}
PAPER_WINDOWS_S = 12 * 5.0


def _used_mib() -> float:
    fields = dict(line.split(":", 1) for line in Path("/proc/meminfo").read_text().splitlines())
    kib = int(fields["MemTotal"].split()[0]) - int(fields["MemAvailable"].split()[0])
    return kib / 1024


class _PeakMemory(threading.Thread):
    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.base_mib = _used_mib()
        self.peak_mib = self.base_mib
        self.done = threading.Event()

    def run(self) -> None:
        while not self.done.wait(0.2):
            self.peak_mib = max(self.peak_mib, _used_mib())


def measure(n_uav: int, windows: int, seed: int, out: Path) -> dict:
    bs = 2 if n_uav <= 20 else 4
    cfg = CONFIG.format(n=n_uav, bs=bs)
    run_dir = out / f"uav{n_uav}"
    if run_dir.exists():
        raise SystemExit(f"error: {run_dir} exists (sizing writes a fresh run per size)")
    mem = _PeakMemory()
    mem.start()
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    r = subprocess.run([*UAVCAS, "run", cfg, "--seed", str(seed), "--windows", str(windows), "--out", str(run_dir)],
                       capture_output=True, text=True)
    wall_s = time.monotonic() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    mem.done.set()
    mem.join()
    if r.returncode != 0:
        raise SystemExit(f"error: {cfg}: exit {r.returncode}: {(r.stdout + r.stderr)[-500:]}")
    info = json.loads((run_dir / "run.json").read_text())
    fid = json.loads((run_dir / "fidelity.json").read_text())
    cpu_s = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    schedule_s = windows * info["window_s"]
    pcap_mib = sum(p.stat().st_size for p in (run_dir / "pcap").glob("*.pcap")) / 2**20
    return {"n_uav": n_uav, "n_bs": bs, "config": cfg, "seed": seed, "windows": windows,
            "wall_s": round(wall_s, 1), "overhead_s": round(wall_s - schedule_s, 1),
            "peak_memory_mib": round(mem.peak_mib - mem.base_mib), "cpu_s": round(cpu_s, 1),
            "cores_busy": round(cpu_s / wall_s, 2), "packets": info["packets_captured"],
            "capture_drops": info["capture_drops"], "capture_mib_per_min": round(pcap_mib / (schedule_s / 60), 1),
            "fidelity": fid["verdict"], "failed": fid["failed"], "delay_error_p99_ms": fid["delay_error_p99_ms"],
            "window_change_max_ms": fid["window_change_max_ms"], "throughput_ratio_p50": fid["throughput_ratio_p50"]}


def paper_night(rows: list[dict], night_h: float) -> dict | None:
    over = {r["n_uav"]: r["overhead_s"] for r in rows}
    if not {5, 10, 20} <= over.keys():
        return None
    over[15] = (over[10] + over[20]) / 2
    total_s = sum(k * (over[n] + PAPER_WINDOWS_S) for n, k in PAPER_SIZES.items())
    return {"runs": sum(PAPER_SIZES.values()), "one_host_h": round(total_s / 3600, 1), "night_h": night_h,
            "hosts": math.ceil(total_s / (night_h * 3600))}


def table(rows: list[dict]) -> str:
    head = ("| UAVs | BSs | wall s | overhead s | peak memory MiB | CPU s | cores busy | capture MiB/min | "
            "packets | fidelity | p99 ms | window change max ms |")
    lines = [head, "|" + "---:|" * 9 + "---|---:|---:|"]
    for r in rows:
        verdict = r["fidelity"] + (f" ({', '.join(r['failed'])})" if r["failed"] else "")
        lines.append(f"| {r['n_uav']} | {r['n_bs']} | {r['wall_s']} | {r['overhead_s']} | {r['peak_memory_mib']} | "
                     f"{r['cpu_s']} | {r['cores_busy']} | {r['capture_mib_per_min']} | {r['packets']:,} | {verdict} | "
                     f"{r['delay_error_p99_ms']} | {r['window_change_max_ms']} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="5,10,20,50,100")
    ap.add_argument("--windows", type=int, default=4)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--night-h", type=float, default=8.0)
    ap.add_argument("--out", type=Path, default=Path("/tmp/sizing"))
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    try:
        sizes = [int(s) for s in a.sizes.split(",")]
    except ValueError:
        raise SystemExit(f"error: --sizes: {a.sizes!r} is not a comma-separated list of integers") from None
    a.out.mkdir(parents=True, exist_ok=True)
    rows = []
    for n in sizes:
        rows.append(measure(n, a.windows, a.seed, a.out))
        print(json.dumps(rows[-1]), flush=True)
    night = paper_night(rows, a.night_h)
    print(table(rows))
    if night:
        print(f"paper preset: {night['runs']} runs, {night['one_host_h']} h on one host; "
              f"{night['hosts']} hosts for a {night['night_h']:g}-hour night")
    if a.json:
        a.json.write_text(json.dumps({"rows": rows, "paper_night": night}, indent=1))


if __name__ == "__main__":
    main()
