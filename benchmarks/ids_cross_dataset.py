"""Cross-dataset binary table (paper table tab:baseline_f1): Benign-vs-DoS weighted F1 of the
baselines on our dataset and on the external samples, one column per dataset.

    .venv/bin/python benchmarks/ids_cross_dataset.py [DATASET_DIR] [--epochs 50] [--models all]
        [--external ../shared/data/ids-samples/cicids2017-improved-rnd2500 ...] [--out table.csv]

Without DATASET_DIR a 20k-flow synthetic uavcas dataset stands in for ours. External samples go
through `uavcas.dataset.read.load_any` (the one dataset reader); they have no runs, so their split
is a stratified flow-level one (stated in each protocol's notes). Every dataset must hold the
`cic` feature standard (CICFlowMeter's definitions and units, as CICIDS2017 itself), so the
columns compare the same quantities; a `paper`-standard dataset is refused.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "ids-samples"
DEFAULT_EXTERNAL = [SHARED / "cicids2017-improved-rnd2500", SHARED / "unsw-nb15-testing-head4528"]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", nargs="?", type=Path)
    ap.add_argument("--external", type=Path, nargs="*", default=[p for p in DEFAULT_EXTERNAL if p.is_dir()])
    ap.add_argument("--models", default="all")
    ap.add_argument("--epochs", type=int, default=50)
    ap.add_argument("--scaler", default="standard")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()

    import pandas as pd

    from uavcas.dataset.read import load_any
    from uavcas.dataset.synthetic import make_flows, write_dataset
    from uavcas.ids.detectors import baselines
    from uavcas.ids.protocols import BenchConfig, run_protocol
    from uavcas.ids.results import results_frame

    ours = args.dataset or write_dataset(Path(tempfile.mkdtemp()) / "uavcas-synthetic",
                                         make_flows(400, flows_per_run=50))
    models = tuple(s.name for s in baselines()) if args.models == "all" else tuple(args.models.split(","))
    cfg = BenchConfig(models=models, scaler=args.scaler, epochs=args.epochs, seeds=(0,), importance=False,
                      n_threads=args.threads or None)
    cols = {}
    for path in [*args.external, ours]:
        df = load_any(path)
        if df.attrs.get("feature_standard", "cic") != "cic":
            raise SystemExit(f"{path}: {df.attrs['feature_standard']} features; the comparison needs cic (extract "
                             "--features cic)")
        res = run_protocol(df, "binary", cfg)
        df = results_frame(res)
        w = df[(df["metric"] == "f1_weighted") & (df["class"] == "")].set_index("model")["value"]
        cols[Path(path).name] = w * 100
        print(f"{Path(path).name}: flows per split {res.sizes}" + "".join(f"; {n}" for n in res.notes), flush=True)
    table = pd.DataFrame(cols)
    table.index.name = "model"
    print("\nBinary Benign-vs-DoS weighted F1 (%)\n")
    print(table.round(2).to_string())
    if args.out:
        from uavcas.atomic import atomic_write_text

        atomic_write_text(args.out, table.to_csv())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
