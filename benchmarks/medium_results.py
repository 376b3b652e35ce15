"""Tables of docs/results.md from a `bench ids` output, beside the paper's numbers.

usage: python benchmarks/medium_results.py BENCH_DIR [BENCH_DIR ...] --out docs/results
Reads each BENCH_DIR's leaderboard.csv (protocol, model, metric, class, mean, std); writes
OUT/medium-leaderboard.csv (all of them, one file) and OUT/medium-tables.md (the tables that
docs/results.md quotes). The paper's values are those of its Tables 'tab:baseline_f1',
'tab:per_attack' and 'tab:collab_f1' (percent), copied here as published.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

MODELS = ["LR", "SGD", "RF", "MLP", "LightGBM", "1D-CNN", "LSTM", "ConvNet", "TinyML", "CNN-BiLSTM"]
CONTEXT = ["Context", "Context-joint", "Context-flow", "Context-only"]
# paper, binary Benign-vs-DoS weighted F1 (%) on UAV-CAS
PAPER_BINARY = {"1D-CNN": 99.98, "LSTM": 98.86, "RF": 99.99, "SGD": 99.98, "LR": 99.99, "MLP": 99.98,
                "LightGBM": 99.96, "ConvNet": 99.99, "TinyML": 99.98, "CNN-BiLSTM": 99.99}
PAPER_CLASSES = ["Benign", "DoS", "DDoS", "Blackhole", "Wormhole", "Replay", "Blackhole+DoS", "Blackhole+DDoS",
                 "Blackhole+Replay", "Blackhole+Wormhole", "DDoS+Replay", "DDoS+Wormhole", "DoS+Replay",
                 "DoS+Wormhole", "Replay+Wormhole"]
# paper, 15-class per-class F1 (%), columns in PAPER_CLASSES order
PAPER_PER_CLASS = {
    "1D-CNN": [22.03, 15.53, 40.35, 7.11, 7.79, 3.24, 5.67, 16.24, 0.72, 4.32, 10.34, 11.81, 5.03, 7.09, 0.79],
    "LSTM": [12.80, 5.85, 6.30, 8.59, 0.00, 0.81, 0.91, 0.00, 0.16, 1.57, 3.64, 9.52, 0.94, 2.93, 0.07],
    "RF": [42.91, 36.17, 47.77, 21.45, 24.42, 7.55, 37.09, 58.15, 3.05, 20.87, 28.58, 61.05, 28.64, 39.42, 6.86],
    "SGD": [53.00, 27.21, 27.84, 9.24, 6.97, 3.32, 11.87, 29.26, 2.11, 4.72, 20.60, 28.98, 32.22, 11.88, 7.22],
    "LR": [62.44, 26.85, 38.21, 19.00, 18.97, 3.93, 12.54, 33.72, 3.24, 16.11, 27.77, 37.78, 21.34, 20.16, 4.25],
    "MLP": [18.42, 10.56, 17.79, 12.64, 5.61, 3.16, 2.54, 11.03, 1.00, 4.95, 11.04, 8.18, 2.91, 4.70, 0.99],
    "LightGBM": [55.59, 67.49, 68.13, 53.04, 55.63, 14.34, 78.65, 81.52, 7.48, 38.21, 33.62, 81.85, 40.58, 77.06, 7.61],
    "ConvNet": [31.46, 11.56, 45.65, 16.19, 15.33, 4.05, 2.31, 12.37, 0.77, 4.42, 11.61, 13.29, 3.66, 8.18, 1.65],
    "TinyML": [51.17, 36.66, 52.91, 32.24, 36.32, 9.05, 37.98, 62.79, 3.55, 28.70, 27.57, 59.50, 16.95, 35.38, 4.26],
    "CNN-BiLSTM": [40.67, 4.15, 9.48, 4.54, 0.00, 2.53, 0.51, 2.72, 0.27, 0.57, 2.61, 20.17, 1.63, 1.40, 0.42],
}
# paper, OOD AUROC (%) per collaborative composition, models in MODELS order
PAPER_OOD = {
    "Blackhole+DoS": [95.67, 92.96, 96.42, 94.26, 98.60, 96.73, 77.32, 98.50, 92.61, 95.66],
    "Blackhole+DDoS": [94.26, 72.24, 93.40, 96.92, 99.69, 97.01, 80.93, 98.58, 92.59, 93.61],
    "DoS+Wormhole": [96.98, 94.06, 90.23, 94.03, 99.52, 97.39, 75.68, 99.34, 90.56, 95.69],
    "DDoS+Wormhole": [92.87, 78.72, 92.62, 94.59, 99.43, 95.13, 78.56, 96.74, 93.35, 88.09],
    "Blackhole+Wormhole": [51.31, 50.75, 85.80, 70.95, 84.97, 60.67, 52.65, 57.44, 86.37, 69.14],
    "Blackhole+Replay": [83.50, 62.58, 78.32, 82.68, 81.74, 73.42, 53.88, 52.99, 77.50, 72.97],
    "DDoS+Replay": [91.87, 81.03, 93.06, 94.51, 99.99, 94.68, 74.71, 93.97, 88.51, 88.30],
    "DoS+Replay": [93.29, 87.19, 94.69, 92.22, 99.58, 94.36, 75.08, 94.78, 89.48, 94.74],
    "Replay+Wormhole": [96.24, 88.03, 86.05, 93.92, 81.42, 84.30, 57.79, 57.15, 86.30, 95.03],
}


def _cell(row: pd.Series | None, pct: bool = True, digits: int = 1) -> str:
    if row is None or pd.isna(row["mean"]):
        return "-"
    k = 100.0 if pct else 1.0
    return f"{row['mean'] * k:.{digits}f} ± {row['std'] * k:.{digits}f}"


def _get(lb: pd.DataFrame, protocol: str, model: str, metric: str, cls: str = "") -> pd.Series | None:
    m = lb[(lb.protocol == protocol) & (lb.model == model) & (lb.metric == metric) & (lb["class"].fillna("") == cls)]
    return None if m.empty else m.iloc[0]


def _per_model(lb: pd.DataFrame, models: list[str], protocol: str, title: str,
               columns: list[tuple[str, str, str, bool, int]], paper: dict | None = None) -> list[str]:
    """One row per model; columns are (header, metric, class, in percent, digits)."""
    head = ["model"] + (["paper"] if paper is not None else []) + [c[0] for c in columns]
    rows = [f"### {title}", "", "| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for m in models:
        cells = ([str(paper.get(m, "-"))] if paper is not None else []) + [
            _cell(_get(lb, protocol, m, metric, cls), pct=pct, digits=digits) for _, metric, cls, pct, digits in columns]
        rows.append(f"| {m} | " + " | ".join(cells) + " |")
    return rows + [""]


def tables(lb: pd.DataFrame) -> str:
    models = [m for m in MODELS + CONTEXT if m in set(lb.model)]
    out = []
    if "binary" in set(lb.protocol):
        out += _per_model(lb, models, "binary", "Binary (Benign vs DoS), weighted F1 %",
                          [("ours (mean ± std over seeds)", "f1_weighted", "", True, 2), ("AUROC %", "auroc", "", True, 2),
                           ("fit s", "fit_s", "", False, 1)], paper=PAPER_BINARY)
    if "multiclass" in set(lb.protocol):
        mc = lb[lb.protocol == "multiclass"]
        classes = [c for c in PAPER_CLASSES if c in set(mc[mc.metric == "f1"]["class"])]
        out += ["### Multiclass, per-class F1 % (ours; the paper's in brackets)", "",
                "| model | " + " | ".join(classes) + " | macro | stealth | fit s |", "|---" * (len(classes) + 4) + "|"]
        for m in models:
            cells = []
            for c in classes:
                ours = _get(lb, "multiclass", m, "f1", c)
                paper = PAPER_PER_CLASS.get(m, [None] * 15)[PAPER_CLASSES.index(c)]
                cells.append(f"{_cell(ours)} [{paper if paper is not None else '-'}]")
            out.append(f"| {m} | " + " | ".join(cells) + f" | {_cell(_get(lb, 'multiclass', m, 'f1_macro'))} | "
                       f"{_cell(_get(lb, 'multiclass', m, 'f1_macro', 'stealth'))} | "
                       f"{_cell(_get(lb, 'multiclass', m, 'fit_s'), pct=False)} |")
        out.append("")
    if "ood" in set(lb.protocol):
        od = lb[(lb.protocol == "ood") & (lb.metric == "auroc")]
        comps = [c for c in PAPER_OOD if c in set(od["class"].dropna())]
        out += ["### OOD: trained on single attacks, AUROC % per unseen collaborative composition (paper in brackets)", "",
                "| composition | " + " | ".join(models) + " |", "|---" * (len(models) + 1) + "|"]
        for c in comps:
            cells = []
            for m in models:
                paper = PAPER_OOD[c][MODELS.index(m)] if m in MODELS else None
                cells.append(f"{_cell(_get(lb, 'ood', m, 'auroc', c))}" + (f" [{paper}]" if paper is not None else ""))
            out.append(f"| {c} | " + " | ".join(cells) + " |")
        out.append("")
    if "cross-condition" in set(lb.protocol):
        out += _per_model(lb, models, "cross-condition", "Cross-condition (a held-out channel setting), %",
                          [("weighted F1 held-out", "f1_weighted", "", True, 1), ("macro F1 held-out", "f1_macro", "", True, 1),
                           ("stealth macro F1 held-out", "f1_macro", "stealth", True, 1),
                           ("macro F1 seen settings", "f1_macro_iid", "", True, 1)])
    if "multiclass" in set(lb.protocol):
        cols = [("f1_macro", "stealth"), ("f1_macro", ""), ("f1", "Blackhole"), ("f1", "Wormhole"), ("f1", "Replay"),
                ("f1", "Replay+Wormhole"), ("f1", "DoS"), ("f1", "DDoS")]
        out += ["### Context detector and ablation beside the best baselines (multiclass %, binary weighted F1)", "",
                "| model | stealth macro-F1 | macro-F1 | Blackhole | Wormhole | Replay | Replay+Wormhole | DoS | DDoS | binary weighted F1 |",
                "|---" * 10 + "|"]
        stealth = {m: _get(lb, "multiclass", m, "f1_macro", "stealth") for m in MODELS}
        best = max((m for m in MODELS if stealth[m] is not None), key=lambda m: stealth[m]["mean"], default=None)
        for m in [x for x in CONTEXT if x in models] + ([best] if best else []):
            cells = [_cell(_get(lb, "multiclass", m, metric, cls)) for metric, cls in cols]
            label = f"{m} (best baseline)" if m == best else m
            out.append(f"| {label} | " + " | ".join(cells) + f" | {_cell(_get(lb, 'binary', m, 'f1_weighted'), pct=False, digits=4)} |")
        out.append("")
    fits = [(m, {p: _get(lb, p, m, "fit_s") for p in ("binary", "multiclass", "ood", "cross-condition")}) for m in models]
    out += ["### Fit time per model, s (mean ± std over seeds; training capped at 300 flows per run and class)", "",
            "| model | binary | multiclass | ood | cross-condition |", "|---|---|---|---|---|"]
    for m, f in fits:
        out.append(f"| {m} | " + " | ".join(_cell(f[p], pct=False) for p in f) + " |")
    out.append("")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("bench_dirs", nargs="+", type=Path)
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args()
    lb = pd.concat([pd.read_csv(d / "leaderboard.csv", keep_default_na=False, na_values=[""]) for d in a.bench_dirs])
    lb = lb.drop_duplicates(["protocol", "model", "metric", "class"], keep="last")
    a.out.mkdir(parents=True, exist_ok=True)
    lb.to_csv(a.out / "medium-leaderboard.csv", index=False)
    (a.out / "medium-tables.md").write_text(tables(lb) + "\n")
    print(a.out / "medium-leaderboard.csv", len(lb), "rows")


if __name__ == "__main__":
    main()
