"""Fidelity benchmark: real runs audited packet by packet (issue #14's targets), per design option.

    sudo .venv/bin/python benchmarks/fidelity_bench.py [--cases 20-benign,20-dos,20-ddos,50-dos,100-benign]
        [--variants default] [--windows 6] [--out DIR] [--json F] [--keep]

Each case is one `uavcas run` of a scenario (6 windows of 5 s) followed by `uavcas audit`;
a variant switches a design option of the delay stage off, to measure what it buys:

| variant     | what changes                                                              |
|-------------|---------------------------------------------------------------------------|
| default     | compiled verdict loop, kernel receive stamps, SCHED_FIFO, softirq boost   |
| python      | the pure-Python verdict loop (UAVCAS_DELAY_IMPL=python)                    |
| no-softirq  | softirq threads left at normal priority (RunOptions.softirq_boost=False)  |
| no-urgent   | window changes and attack actions at normal priority (RunOptions.urgent)  |

Reported per run: pooled per-hop delay error p50/p90/p99/p99.9 (ms, measured - FIFO model),
fraction of crossings > 1 ms late, longest window change and lateness (ms), the verdict, and the
load average over the run (other jobs share the cores: always read the figures with it).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from uavcas.atomic import atomic_write_text
from uavcas.emulation import nfqdelay
from uavcas.emulation.preflight import probe_kernel
from uavcas.emulation.runner import RunOptions, realize
from uavcas.fidelity import write_fidelity
from uavcas.twin.plan import plan

CASES = {
    "20-benign": "benign-20-2-image-logdist-adaptive-random-30-95",
    "20-dos": "dos=1000-20-2-image-logdist-adaptive-random-30-95",
    "20-ddos": "ddos=1000-20-2-image-logdist-adaptive-random-30-95",
    "50-dos": "dos=1000-50-4-image-logdist-adaptive-random-30-95",
    "100-benign": "benign-100-4-image-logdist-adaptive-random-30-95",
}
VARIANTS = {
    "default": ({}, RunOptions()),
    "python": ({nfqdelay.IMPL_ENV: "python"}, RunOptions()),
    "no-softirq": ({}, RunOptions(softirq_boost=False)),
    "no-urgent": ({}, RunOptions(urgent=False)),
}


def one(case: str, variant: str, windows: int, out_dir: Path) -> dict:
    env, opts = VARIANTS[variant]
    p = plan(CASES[case], seed=0, windows=windows, window_s=5.0)
    feats, reason = probe_kernel()
    if reason:
        raise SystemExit(reason)
    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    load0 = os.getloadavg()[0]
    t0 = time.time()
    try:
        art = realize(p, out_dir, opts, features=feats)  # not audited: timed below
    finally:
        for k, v in saved.items():
            os.environ.pop(k, None) if v is None else os.environ.__setitem__(k, v)
    wall = time.time() - t0
    load1 = os.getloadavg()[0]
    t1 = time.time()
    f = write_fidelity(out_dir)
    info = art.run_info
    return {
        "case": case, "variant": variant, "config": p.config, "exit": art.exit_status, "wall_s": round(wall, 1),
        "audit_s": round(time.time() - t1, 1), "load_before": round(load0, 2), "load_after": round(load1, 2),
        "verdict": f.verdict, "failed": f.failed, "crossings": f.n,
        "p50_ms": f.delay_error_p50_ms, "p90_ms": f.delay_error_p90_ms, "p99_ms": f.delay_error_p99_ms,
        "p999_ms": f.delay_error_p999_ms, "late_over_1ms": f.late_over_1ms,
        "window_change_max_ms": f.window_change_max_ms, "lateness_max_ms": f.lateness_max_ms,
        "lost": f.lost, "lost_random": f.loss_random_observed, "gap_shift_p90_ms": f.gaps.shift_p90_ms,
        "delay_impl": (info.delay_daemon or {}).get("impl") if info else None,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--variants", default="default")
    ap.add_argument("--windows", type=int, default=6)
    ap.add_argument("--out", type=Path, default=None, help="keep run directories here (default: temporary)")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    if os.geteuid() != 0:
        raise SystemExit("fidelity_bench needs root (it runs real emulations)")
    base = args.out or Path(tempfile.mkdtemp(prefix="uavcas-fidelity-"))
    rows = []
    try:
        for variant in args.variants.split(","):
            for case in args.cases.split(","):
                r = one(case, variant, args.windows, base / f"{case}-{variant}")
                rows.append(r)
                print(json.dumps(r), flush=True)
                if args.out is None:
                    shutil.rmtree(base / f"{case}-{variant}", ignore_errors=True)
    finally:
        if args.out is None:
            shutil.rmtree(base, ignore_errors=True)
    print("\n| case | variant | load | p50 | p90 | p99 | p99.9 ms | >1 ms | window change ms | late ms | verdict |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in rows:
        print(f"| {r['case']} | {r['variant']} | {r['load_before']:.1f}-{r['load_after']:.1f} | {r['p50_ms']} | "
              f"{r['p90_ms']} | {r['p99_ms']} | {r['p999_ms']} | {100 * (r['late_over_1ms'] or 0):.2f} % | "
              f"{r['window_change_max_ms']} | {r['lateness_max_ms']} | {r['verdict']} |")
    if args.json:
        atomic_write_text(args.json, json.dumps(rows, indent=1) + "\n")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
