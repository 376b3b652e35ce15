"""The leaderboard: every protocol's scores as mean and standard deviation over the seeds
(columns protocol, model, metric, class, mean, std; class "" for overall metrics, "stealth" for
the macro-F1 over the stealth classes), and its markdown, laid out like the paper's tables:
binary and multiclass models x metrics, 15-class per-class F1, OOD compositions x models (AUROC),
cross-condition held-out vs seen-condition scores, and fit times.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .detectors import detectors
from .metrics import STEALTH

COLUMNS = ("protocol", "model", "metric", "class", "mean", "std")
PROTOCOL_ORDER = ("binary", "multiclass", "ood", "cross-condition")
MODEL_ORDER = [s.display for s in detectors()]
# overall columns of each protocol's main table: (metric, class, header)
MAIN: dict[str, tuple[tuple[str, str, str], ...]] = {
    "binary": (("f1_weighted", "", "weighted F1"), ("f1_macro", "", "macro F1"), ("auroc", "", "AUROC"),
               ("pr_auc", "", "PR-AUC"), ("fit_s", "", "fit s")),
    "multiclass": (("f1_macro", "", "macro F1"), ("f1_weighted", "", "weighted F1"),
                   ("f1_macro", STEALTH, "stealth macro F1"), ("pr_auc_macro", "", "macro PR-AUC"),
                   ("accuracy", "", "accuracy"), ("fit_s", "", "fit s")),
    "ood": (("auroc", "", "AUROC (in-distribution)"), ("pr_auc", "", "PR-AUC (in-distribution)"),
            ("fit_s", "", "fit s")),
    "cross-condition": (("f1_macro", "", "macro F1 held-out"), ("f1_macro_iid", "", "macro F1 seen"),
                        ("f1_macro", STEALTH, "stealth held-out"), ("f1_weighted", "", "weighted F1 held-out"),
                        ("fit_s", "", "fit s")),
}


def summarize(results: pd.DataFrame) -> pd.DataFrame:
    """Mean and sample standard deviation over seeds (std empty with a single seed)."""
    g = results.groupby(["protocol", "model", "metric", "class"], sort=False)["value"]
    out = g.agg(mean="mean", std=lambda v: float(v.std(ddof=1)) if v.notna().sum() > 1 else np.nan).reset_index()
    return out.reindex(columns=list(COLUMNS))


def _cell(mean: float, std: float, digits: int) -> str:
    if mean is None or (isinstance(mean, float) and math.isnan(mean)):
        return ""
    s = f"{mean:.{digits}f}"
    return s if std is None or math.isnan(std) else f"{s} ± {std:.{digits}f}"


def _table(rows: list[str], cols: list[str], cell) -> str:
    lines = ["| | " + " | ".join(cols) + " |", "|---|" + "---|" * len(cols)]
    lines += ["| " + r + " | " + " | ".join(cell(r, c) for c in cols) + " |" for r in rows]
    return "\n".join(lines)


def _models(sub: pd.DataFrame) -> list[str]:
    present = list(dict.fromkeys(sub["model"]))
    return [m for m in MODEL_ORDER if m in present] + [m for m in present if m not in MODEL_ORDER]


def protocol_markdown(summary: pd.DataFrame, protocol: str) -> str:
    sub = summary[summary["protocol"] == protocol]
    if sub.empty:
        return ""
    idx = {(r.model, r.metric, r["class"]): (r["mean"], r["std"]) for _, r in sub.iterrows()}
    models = _models(sub)
    main = [m for m in MAIN.get(protocol, ()) if any((mo, m[0], m[1]) in idx for mo in models)]
    heads = [h for _, _, h in main]
    by_head = {h: (m, c) for m, c, h in main}

    def overall(model: str, head: str) -> str:
        m, c = by_head[head]
        mean, std = idx.get((model, m, c), (np.nan, np.nan))
        return _cell(mean, std, 1 if m == "fit_s" else 4)

    parts = [f"### {protocol}", "", _table(models, heads, overall), ""]
    if protocol in ("multiclass", "cross-condition"):
        classes = list(dict.fromkeys(sub[(sub["metric"] == "f1") & (sub["class"] != "")]["class"]))
        if classes:
            parts += [f"Per-class F1 ({'held-out condition' if protocol == 'cross-condition' else 'test runs'}):", "",
                      _table(models, classes, lambda mo, c: _cell(*idx.get((mo, "f1", c), (np.nan, np.nan)), 2)), ""]
    if protocol == "ood":
        comps = [c for c in dict.fromkeys(sub[(sub["metric"] == "auroc") & (sub["class"] != "")]["class"])]
        if comps:
            parts += ["AUROC per collaborative composition (never trained on):", "",
                      _table(comps, models, lambda c, mo: _cell(*idx.get((mo, "auroc", c), (np.nan, np.nan)), 3)), ""]
    return "\n".join(parts)


def leaderboard_markdown(summary: pd.DataFrame, title: str = "IDS leaderboard", notes: list[str] | None = None) -> str:
    protocols = [p for p in PROTOCOL_ORDER if p in set(summary["protocol"])]
    protocols += [p for p in dict.fromkeys(summary["protocol"]) if p not in protocols]
    parts = [f"# {title}", "", "Mean ± standard deviation over the seeds (a new grouped split and model seed each).",
             ""]
    parts += [f"- {n}" for n in notes or []] + ([""] if notes else [])
    parts += [protocol_markdown(summary, p) for p in protocols]
    return "\n".join(parts)
