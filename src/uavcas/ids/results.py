"""Writing a benchmark's results: results.csv (long format), results.json, results.md, confusion
matrices (CSV) and the best/worst confusion figure. Every file atomically."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from uavcas.atomic import atomic_write_text

from .protocols import ProtocolResult

RESULT_COLUMNS = ("protocol", "model", "metric", "class", "value")


def results_frame(res: ProtocolResult) -> pd.DataFrame:
    return pd.DataFrame(res.rows, columns=list(RESULT_COLUMNS))


def _md_table(df: pd.DataFrame, fmt: str = "{:.4f}") -> str:
    cols = [str(c) for c in df.columns]
    lines = ["| " + " | ".join([df.index.name or ""] + cols) + " |", "|" + "---|" * (len(cols) + 1)]
    for idx, row in df.iterrows():
        cells = [fmt.format(v) if isinstance(v, float) and not math.isnan(v) else ("" if isinstance(v, float) else str(v)) for v in row]
        lines.append("| " + " | ".join([str(idx)] + cells) + " |")
    return "\n".join(lines)


def markdown(res: ProtocolResult, meta: dict) -> str:
    df = results_frame(res)
    order = list(dict.fromkeys(df["model"]))
    parts = [f"# IDS benchmark: {res.protocol}", "", f"dataset: `{meta.get('dataset')}`, scaler: {meta.get('scaler')}, "
             f"epochs: {meta.get('epochs')}, seed: {meta.get('seed')}", ""]
    if res.notes:
        parts += ["Notes: " + "; ".join(res.notes), ""]
    parts += ["Split sizes: " + ", ".join(f"{k} {v}" for k, v in res.splits.items()), ""]
    overall = df[df["class"] == ""].pivot(index="model", columns="metric", values="value").reindex(order)
    if not overall.empty:
        parts += ["## Overall", "", _md_table(overall), ""]
    per = df[df["class"] != ""]
    for metric in dict.fromkeys(per["metric"]):
        t = per[per["metric"] == metric].pivot(index="model", columns="class", values="value").reindex(order)
        t = t[list(dict.fromkeys(per[per["metric"] == metric]["class"]))]
        parts += [f"## {metric} per class", "", _md_table(t), ""]
    if res.timings:
        tt = pd.DataFrame({"seconds": pd.Series(res.timings), "epochs": pd.Series(res.epochs_run, dtype=float)}).reindex(order)
        tt.index.name = "model"
        parts += ["## Fit + predict time", "", _md_table(tt, "{:.1f}"), ""]
    return "\n".join(parts)


def confusion_figure(res: ProtocolResult, path: Path) -> Path | None:
    """Confusion matrices (row-normalised) of the best and the worst model by macro F1."""
    if not res.confusion:
        return None
    from uavcas.report.figure import plt, save_png

    df = results_frame(res)
    f1 = df[(df["metric"] == "f1_macro") & (df["class"] == "")].set_index("model")["value"]
    f1 = f1[f1.index.isin(res.confusion)]
    if f1.empty:
        return None
    picks = [("best", f1.idxmax()), ("worst", f1.idxmin())]
    fig, axes = plt.subplots(1, 2, figsize=(14, 6.5))
    for ax, (tag, model) in zip(axes, picks):
        labels, cm = res.confusion[model]
        norm = cm / np.maximum(cm.sum(1, keepdims=True), 1)
        ax.imshow(norm, cmap="Blues", vmin=0, vmax=1)
        ax.set_xticks(range(len(labels)), labels, rotation=90, fontsize=7)
        ax.set_yticks(range(len(labels)), labels, fontsize=7)
        ax.set_xlabel("predicted")
        ax.set_ylabel("true")
        ax.set_title(f"{tag}: {model} (macro F1 {f1[model]:.3f})")
    return save_png(fig, path)


def write_results(res: ProtocolResult, out: str | Path, meta: dict) -> list[Path]:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    df = results_frame(res)
    written = [atomic_write_text(out / "results.csv", df.to_csv(index=False))]
    payload = {**meta, "protocol": res.protocol, "splits": res.splits, "notes": res.notes,
               "timings_s": res.timings, "epochs_run": res.epochs_run, "results": json.loads(df.to_json(orient="records"))}
    written.append(atomic_write_text(out / "results.json", json.dumps(payload, indent=2, default=str)))
    written.append(atomic_write_text(out / "results.md", markdown(res, meta)))
    for model, (labels, cm) in res.confusion.items():
        name = "confusion_" + "".join(ch if ch.isalnum() else "_" for ch in model) + ".csv"
        written.append(atomic_write_text(out / name, pd.DataFrame(cm, index=labels, columns=labels).to_csv()))
    fig = confusion_figure(res, out / "confusion_best_worst.png")
    if fig:
        written.append(fig)
    return written
