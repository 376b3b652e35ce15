"""The torch baselines' fits on the CPU against a CUDA GPU, side by side on one machine (issue 25).

One protocol (multiclass by default), the five deep baselines, the same dataset, split, seeds and
epochs; each device in turn, in one process: `TorchClassifier(device=...)` through
`uavcas.ids.protocols` exactly as `uavcas bench ids --device` runs them. Prints and writes
(--json) the fit seconds (training and scoring the test split) per model, seed and device, the
epochs each ran, macro-F1 per device (a sanity check that both learned the same task, not a
benchmark figure), and what the machine was (CPU threads, GPU name, torch version).

usage: python benchmarks/torch_devices.py DATASET [--protocol multiclass] [--seeds 0] [--epochs 15]
       [--train-cap 300] [--threads 0] [--devices cpu,cuda] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="torch_devices.py")
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--protocol", default="multiclass")
    ap.add_argument("--seeds", default="0")
    ap.add_argument("--epochs", type=int, default=15)
    ap.add_argument("--train-cap", type=int, default=300)
    ap.add_argument("--threads", type=int, default=0, help="CPU threads per model (0: the cores available)")
    ap.add_argument("--devices", default="cpu,cuda")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)

    import torch

    from uavcas.dataset.read import load_any
    from uavcas.ids.detectors import detectors
    from uavcas.ids.protocols import BenchConfig, execute, prepare
    from uavcas.ids.torch_estimator import default_threads

    devices = [d.strip() for d in a.devices.split(",") if d.strip()]
    if "cuda" in devices and not torch.cuda.is_available():
        print("torch sees no CUDA GPU: run with --devices cpu, or on a machine with one", file=sys.stderr)
        return 2
    df = load_any(a.dataset)
    seeds = tuple(int(s) for s in a.seeds.split(","))
    threads = a.threads or default_threads()
    rows, f1 = [], {}
    for dev in devices:
        deep = tuple(s.name for s in detectors() if s.needs_torch)
        cfg = BenchConfig(models=deep, epochs=a.epochs, seeds=seeds, importance=False, train_cap=a.train_cap or None,
                          n_threads=threads, device=dev)
        prep = prepare(df, a.protocol, cfg)
        t0 = time.perf_counter()
        res = execute(prep, cfg)
        wall = time.perf_counter() - t0
        for f in res.fits:
            rows.append({"device": dev, "resolved": f.device, "model": f.model, "seed": f.seed,
                         "fit_s": round(f.seconds, 3), "epochs": f.epochs})
        f1[dev] = {s.model: round(s.value, 4) for s in res.scores if s.metric == "f1_macro" and s.cls == ""}
        print(f"{dev}: {wall:.1f} s for {len(res.fits)} fits", flush=True)
    info = {"dataset": str(a.dataset), "flows": len(df), "protocol": a.protocol, "epochs": a.epochs,
            "train_cap": a.train_cap, "seeds": list(seeds), "cpu_threads": threads, "machine": platform.machine(),
            "torch": torch.__version__,
            "gpu": torch.cuda.get_device_name(0) if torch.cuda.is_available() else None,
            "fits": rows, "macro_f1": f1}
    print(f"{'model':12s} " + " ".join(f"{d + ' s':>10s}" for d in devices) + "   epochs")
    for m in sorted({r["model"] for r in rows}):
        secs = [sum(r["fit_s"] for r in rows if r["model"] == m and r["device"] == d) for d in devices]
        ep = sorted({r["epochs"] for r in rows if r["model"] == m})
        print(f"{m:12s} " + " ".join(f"{s:10.1f}" for s in secs) + f"   {ep}")
    if a.json:
        a.json.write_text(json.dumps(info, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
