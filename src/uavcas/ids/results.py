"""Writing one protocol's results (every file atomically):

    results.csv      protocol, seed, model, metric, class, value (class "" = overall)
    summary.csv      protocol, model, metric, class, mean, std over the seeds
    splits.csv       seed, run_id, split (train | val | test | heldout | ood-test)
    confusion.csv    seed, model, true, predicted, count (the main test set of every seed)
    confusion_<model>.csv / .png   counts summed over the seeds, every model
    importance.csv   seed, model, feature, mean, std (permutation importance, tree models)
    results.json     options, declared classes, split sizes, fit times, notes
    results.md       the protocol's tables (leaderboard layout) + split sizes and top features
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd

from uavcas.atomic import atomic_write_text
from uavcas.figure import plt, save_png

from .leaderboard import leaderboard_markdown, summarize
from .protocols import ProtocolResult

RESULT_COLUMNS = ("protocol", "seed", "model", "metric", "class", "value")
TOP_FEATURES = 10


class ResultsError(ValueError):
    """Benchmark outputs that cannot be put on one leaderboard; one line."""


def results_frame(res: ProtocolResult) -> pd.DataFrame:
    df = pd.DataFrame([asdict(s) for s in res.scores], columns=["protocol", "seed", "model", "metric", "cls", "value"])
    return df.rename(columns={"cls": "class"})[list(RESULT_COLUMNS)]


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in name)


def confusion_totals(res: ProtocolResult) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for (_seed, model), cm in res.confusion.items():
        out[model] = out.get(model, 0) + cm
    return out


def confusion_long(res: ProtocolResult) -> pd.DataFrame:
    rows = []
    for (seed, model), cm in res.confusion.items():
        for i, t in enumerate(res.declared):
            for j, p in enumerate(res.declared):
                rows.append((seed, model, t, p, int(cm[i, j])))
    return pd.DataFrame(rows, columns=["seed", "model", "true", "predicted", "count"])


def confusion_figure(labels: list[str], cm: np.ndarray, title: str, path: Path) -> Path:
    """Counts in each cell, colour = share of the true class's flows."""
    n = len(labels)
    size = max(4.0, 0.45 * n + 2)
    fig, ax = plt.subplots(figsize=(size + 1, size))
    norm = cm / np.maximum(cm.sum(1, keepdims=True), 1)
    ax.imshow(norm, cmap="Blues", vmin=0, vmax=1)
    for i in range(n):
        for j in range(n):
            if cm[i, j]:
                ax.text(j, i, str(int(cm[i, j])), ha="center", va="center", fontsize=6 if n > 8 else 8,
                        color="white" if norm[i, j] > 0.6 else "black")
    ax.set_xticks(range(n), labels, rotation=90, fontsize=7)
    ax.set_yticks(range(n), labels, fontsize=7)
    ax.set_xlabel("predicted")
    ax.set_ylabel("true")
    ax.set_title(title, fontsize=9)
    return save_png(fig, path)


def importance_frame(res: ProtocolResult) -> pd.DataFrame:
    return pd.DataFrame([asdict(i) for i in res.importance], columns=["seed", "model", "feature", "mean", "std"])


def markdown(res: ProtocolResult, meta: dict) -> str:
    summary = summarize(results_frame(res))
    seeds = sorted(res.sizes)
    parts = [leaderboard_markdown(summary, f"IDS benchmark: {res.protocol}", res.notes),
             f"dataset: `{meta.get('dataset')}`, scaler: {meta.get('scaler')}, epochs: {meta.get('epochs')}, "
             f"seeds: {', '.join(map(str, seeds))}, features: {len(res.features)}, "
             f"devices: {', '.join(sorted({f.device for f in res.fits})) or 'none'}", "",
             f"Declared classes ({len(res.declared)}): {', '.join(res.declared)}", "",
             "Flows per split: " + "; ".join(f"seed {s}: " + ", ".join(f"{k} {v}" for k, v in res.sizes[s].items())
                                           for s in seeds), ""]
    imp = importance_frame(res)
    if not imp.empty:
        top = imp.groupby(["model", "feature"])["mean"].mean().reset_index()
        parts += ["## Permutation importance (macro-F1 drop, mean over seeds)", ""]
        for model, g in top.groupby("model", sort=False):
            best = g.sort_values("mean", ascending=False).head(TOP_FEATURES)
            parts.append(f"- {model}: " + ", ".join(f"{r.feature} {r.mean:.3f}" for r in best.itertuples()))
        parts.append("")
    return "\n".join(parts)


def write_results(res: ProtocolResult, out: str | Path, meta: dict) -> list[Path]:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    df = results_frame(res)
    written = [atomic_write_text(out / "results.csv", df.to_csv(index=False)),
               atomic_write_text(out / "summary.csv", summarize(df).to_csv(index=False)),
               atomic_write_text(out / "splits.csv",
                                 pd.DataFrame([asdict(s) for s in res.splits],
                                              columns=["seed", "run_id", "split"]).to_csv(index=False)),
               atomic_write_text(out / "confusion.csv", confusion_long(res).to_csv(index=False))]
    imp = importance_frame(res)
    if not imp.empty:
        written.append(atomic_write_text(out / "importance.csv", imp.to_csv(index=False)))
    payload = {**meta, "protocol": res.protocol, "declared": res.declared, "features": res.features,
               "sizes": {str(k): v for k, v in res.sizes.items()}, "notes": res.notes,
               "fits": [asdict(f) for f in res.fits]}
    written.append(atomic_write_text(out / "results.json", json.dumps(payload, indent=2, default=str)))
    written.append(atomic_write_text(out / "results.md", markdown(res, meta)))
    for model, cm in confusion_totals(res).items():
        written.append(atomic_write_text(out / f"confusion_{_safe(model)}.csv",
                                         pd.DataFrame(cm, index=res.declared, columns=res.declared).to_csv()))
        title = f"{res.protocol}: {model} (counts, {len(res.sizes)} seeds)"
        written.append(confusion_figure(res.declared, cm, title, out / f"confusion_{_safe(model)}.png"))
    return written


def write_leaderboard(out: str | Path, results: pd.DataFrame, notes: list[str]) -> list[Path]:
    """leaderboard.csv (`summarize`) and leaderboard.md of results of one or more protocols."""
    out = Path(out)
    summary = summarize(results)
    return [atomic_write_text(out / "leaderboard.csv", summary.to_csv(index=False)),
            atomic_write_text(out / "leaderboard.md", leaderboard_markdown(summary, notes=notes))]


def collect_results(outputs: list[Path]) -> tuple[pd.DataFrame, list[Path]]:
    """The results.csv files of `bench ids` outputs (directories, searched recursively, or the
    files themselves), read into one frame, and the files read. Each protocol must come from one
    file only: its seeds' mean and std would otherwise mix two benchmarks."""
    files: list[Path] = []
    for r in map(Path, outputs):
        found = sorted(r.rglob("results.csv")) if r.is_dir() else ([r] if r.name == "results.csv" else [])
        if not found:
            raise ResultsError(f"{r}: no results.csv (expected a `bench ids` output directory)")
        files += found
    frames = []
    for f in files:
        df = pd.read_csv(f, keep_default_na=False, na_values=[""], dtype={"class": str})
        if list(df.columns) != list(RESULT_COLUMNS):
            raise ResultsError(f"{f}: not a `bench ids` results.csv (columns {list(df.columns)})")
        frames.append(df.fillna({"class": ""}))
    allr = pd.concat(frames, ignore_index=True)
    dup = allr.duplicated(["protocol", "seed", "model", "metric", "class"])
    if dup.any():
        p = allr.loc[dup, "protocol"].iloc[0]
        raise ResultsError(f"protocol {p!r} appears in more than one results.csv: pass each protocol once")
    return allr, files
