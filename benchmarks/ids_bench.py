"""IDS benchmark: `uavcas bench ids` with all ten baselines on a synthetic 100k-flow dataset.

    .venv/bin/python benchmarks/ids_bench.py [--flows 100000] [--epochs 50] [--protocol multiclass]
                                             [--threads 0] [--workdir DIR]

Generates a dataset with the synthetic class structure of `uavcas.analysis.synthetic` (16
compositions cycling over runs of 100 flows, campaign axes, floods separable, wormhole
indistinguishable from benign by construction), writes it as a dataset directory, runs the CLI
once (all ten models, 70/10/20 split grouped by run) and prints wall time and the per-model
fit+predict time and scores from results.json. Not a test: it takes minutes.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flows", type=int, default=100_000)
    ap.add_argument("--flows-per-run", type=int, default=100)
    ap.add_argument("--epochs", type=int, default=50)
    ap.add_argument("--protocol", default="multiclass")
    ap.add_argument("--models", default="all")
    ap.add_argument("--threads", type=int, default=0, help="0: cores available to the process")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workdir", type=Path, default=None, help="keep the dataset and results here")
    args = ap.parse_args()

    from uavcas.analysis.synthetic import make_flows, write_dataset

    work = args.workdir or Path(tempfile.mkdtemp(prefix="uavcas-ids-bench-"))
    t0 = time.perf_counter()
    ds = write_dataset(work / "dataset", make_flows(args.flows, flows_per_run=args.flows_per_run, seed=args.seed))
    t_gen = time.perf_counter() - t0
    print(f"generated {args.flows} flows in {t_gen:.1f} s -> {ds}", flush=True)

    uavcas = Path(sys.executable).with_name("uavcas")
    cmd = [str(uavcas), "bench", "ids", str(ds), "--protocol", args.protocol, "--models", args.models,
           "--epochs", str(args.epochs), "--threads", str(args.threads), "--seed", str(args.seed),
           "--out", str(work / "results")]
    if args.protocol == "cross-condition":
        cmd += ["--holdout", "mission=random"]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        print(proc.stderr[-3000:], file=sys.stderr)
        return proc.returncode
    res = json.loads((work / "results" / "results.json").read_text())
    scores: dict[str, dict[str, float]] = {}
    for r in res["results"]:
        if r["class"] in ("", None):
            scores.setdefault(r["model"], {})[r["metric"]] = r["value"]
    print(f"\nuavcas bench ids --protocol {args.protocol} --epochs {args.epochs}: wall {wall:.1f} s "
          f"(split {res['splits']})\n")
    print(f"| model | fit+predict s | f1_macro | f1_weighted |\n|---|---:|---:|---:|")
    for model, secs in res["timings_s"].items():
        s = scores.get(model, {})
        print(f"| {model} | {secs:.1f} | {s.get('f1_macro', float('nan')):.4f} | {s.get('f1_weighted', float('nan')):.4f} |")
    print(f"\nresults in {work / 'results'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
