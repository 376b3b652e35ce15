"""IDS benchmark: `uavcas bench ids` with all ten baselines on a synthetic 100k-flow dataset.

    .venv/bin/python benchmarks/ids_bench.py [--runs 1000] [--flows-per-run 100] [--epochs 50]
                                             [--protocol multiclass] [--seeds 0] [--threads 0] [--workdir DIR]

Generates a dataset with the synthetic class structure of `uavcas.dataset.synthetic` (the medium
preset's configurations cycling over runs of 100 flows, floods separable, wormhole
indistinguishable from benign by construction), writes it as a dataset directory, runs the CLI
once (all ten models, split grouped by run, one seed by default) and prints wall time and the
per-model fit+predict time and scores. Not a test: it takes minutes.
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
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--flows-per-run", type=int, default=100)
    ap.add_argument("--epochs", type=int, default=50)
    ap.add_argument("--protocol", default="multiclass")
    ap.add_argument("--models", default="all")
    ap.add_argument("--threads", type=int, default=0, help="0: cores available to the process")
    ap.add_argument("--seed", type=int, default=0, help="dataset seed")
    ap.add_argument("--seeds", default="0", help="bench split/model seeds")
    ap.add_argument("--workdir", type=Path, default=None, help="keep the dataset and results here")
    args = ap.parse_args()

    import pandas as pd

    from uavcas.dataset.synthetic import make_flows, write_dataset

    work = args.workdir or Path(tempfile.mkdtemp(prefix="uavcas-ids-bench-"))
    t0 = time.perf_counter()
    ds = write_dataset(work / "dataset", make_flows(args.runs, flows_per_run=args.flows_per_run, seed=args.seed))
    t_gen = time.perf_counter() - t0
    print(f"generated {args.runs * args.flows_per_run} flows in {t_gen:.1f} s -> {ds}", flush=True)

    uavcas = Path(sys.executable).with_name("uavcas")
    cmd = [str(uavcas), "bench", "ids", str(ds), "--protocol", args.protocol, "--models", args.models,
           "--epochs", str(args.epochs), "--threads", str(args.threads), "--seeds", args.seeds, "--no-importance",
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
    summary = pd.read_csv(work / "results" / "summary.csv", keep_default_na=False, na_values=["nan"])
    overall = summary[summary["class"] == ""].pivot(index="model", columns="metric", values="mean")
    print(f"\nuavcas bench ids --protocol {args.protocol} --epochs {args.epochs} --seeds {args.seeds}: "
          f"wall {wall:.1f} s (flows per split {res['sizes']})\n")
    print("| model | fit+predict s | f1_macro | f1_weighted |\n|---|---:|---:|---:|")
    for model, s in overall.iterrows():
        print(f"| {model} | {s.get('fit_s', float('nan')):.1f} | {s.get('f1_macro', float('nan')):.4f} | "
              f"{s.get('f1_weighted', float('nan')):.4f} |")
    print(f"\nresults in {work / 'results'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
