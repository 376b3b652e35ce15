"""Separability: per-class mean/std of key flow features, t-SNE embedding, distribution figures."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from sklearn.manifold import TSNE
from sklearn.preprocessing import StandardScaler

from uavcas import seeding
from uavcas.atomic import atomic_write_text
from uavcas.figure import plt, save_png
from uavcas.flows.standards import DEFAULT_STANDARD, feature_columns

from .diversity import class_order

# (column, display name, scale): IAT shown in ms like the paper's table tab:separability_stats
KEY_FEATURES: tuple[tuple[str, str, float], ...] = (
    ("Flow IAT Mean", "iat_ms", 1e3),
    ("Flow Packets/s", "pkt_rate_pps", 1.0),
    ("Packet Length Mean", "pkt_size_b", 1.0),
    ("Flow Duration", "duration_s", 1.0),
)


def separability_stats(df: pd.DataFrame) -> pd.DataFrame:
    """One row per class: n and mean/std of IAT (ms), packet rate, packet size, duration."""
    missing = [c for c, _, _ in KEY_FEATURES if c not in df.columns]
    if missing or "label" not in df.columns:
        raise ValueError("missing columns for separability: "
                         f"{missing + (['label'] if 'label' not in df.columns else [])}")
    rows = []
    for c in class_order(df["label"].unique()):
        sub = df[df["label"] == c]
        row: dict[str, object] = {"class": c, "n_flows": len(sub)}
        for col, name, scale in KEY_FEATURES:
            v = sub[col].to_numpy(dtype=float) * scale
            row[f"{name}_mean"] = float(np.nanmean(v))
            row[f"{name}_std"] = float(np.nanstd(v, ddof=1)) if len(v) > 1 else 0.0
        rows.append(row)
    return pd.DataFrame(rows)


def _signed_log(x: np.ndarray) -> np.ndarray:
    # why: rates and durations span many decades; t-SNE on raw values sees only the floods
    return np.sign(x) * np.log1p(np.abs(x))


def stratified_sample(labels, n: int, seed: int = 0) -> np.ndarray:
    """Sorted row positions of a seeded subsample of `n` rows with every class as equal a share as
    it can have: classes smaller than their share give all their rows, the rest is shared out
    among the larger ones (so a 8-flow Wormhole is in the plot beside 5,000 DoS flows)."""
    labels = np.asarray(labels)
    if n >= len(labels):
        return np.arange(len(labels))
    rng = seeding.generator(seed)
    classes, counts = np.unique(labels, return_counts=True)
    take = np.zeros(len(classes), dtype=int)
    left = n
    while left > 0:
        open_ = np.flatnonzero(take < counts)
        share = max(1, left // len(open_))
        for i in rng.permutation(open_):
            add = min(share, counts[i] - take[i], left)
            take[i] += add
            left -= add
            if left == 0:
                break
    picks = [rng.choice(np.flatnonzero(labels == c), k, replace=False) for c, k in zip(classes, take) if k]
    return np.sort(np.concatenate(picks))


def tsne_embedding(df: pd.DataFrame, n_samples: int = 2000, seed: int = 0) -> pd.DataFrame:
    """2-D t-SNE of the dataset standard's features (signed log, standardised) on a seeded subsample stratified
    by class (`stratified_sample`)."""
    sub = df.iloc[stratified_sample(df["label"].astype(str).to_numpy(), n_samples, seed)]
    if len(sub) < 5:
        raise ValueError(f"t-SNE needs at least 5 flows, got {len(sub)}")
    cols = list(feature_columns(df.attrs.get("feature_standard", DEFAULT_STANDARD)))
    x = _signed_log(np.nan_to_num(sub[cols].to_numpy(dtype=float)))
    x = StandardScaler().fit_transform(x)
    perplexity = float(min(30, max(2, (len(sub) - 1) // 3)))
    emb = TSNE(n_components=2, perplexity=perplexity, init="pca", random_state=seed).fit_transform(x)
    return pd.DataFrame({"x": emb[:, 0], "y": emb[:, 1], "label": sub["label"].to_numpy()})


def _colors(classes: list[str]) -> dict[str, object]:
    cmap = plt.get_cmap("tab20")
    return {c: cmap(i % 20) for i, c in enumerate(classes)}


def tsne_figure(emb: pd.DataFrame, path: str | Path) -> Path:
    classes = class_order(emb["label"].unique())
    col = _colors(classes)
    fig, ax = plt.subplots(figsize=(7, 6))
    for c in classes:
        m = emb["label"] == c
        ax.scatter(emb.loc[m, "x"], emb.loc[m, "y"], s=4, alpha=0.6, color=col[c], label=c)
    ax.set_title("t-SNE of flow features")
    ax.set_xticks([])
    ax.set_yticks([])
    ax.legend(markerscale=3, fontsize=7, loc="center left", bbox_to_anchor=(1, 0.5))
    return save_png(fig, path)


def distributions_figure(df: pd.DataFrame, path: str | Path) -> Path:
    """Per-class histograms (log x, shared log bins per panel) of the four key features."""
    classes = class_order(df["label"].unique())
    col = _colors(classes)
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    for ax, (feature, name, scale) in zip(axes.ravel(), KEY_FEATURES):
        v = df[feature].to_numpy(dtype=float) * scale
        pos = v[np.isfinite(v) & (v > 0)]
        if pos.size == 0:
            ax.set_title(f"{name}: no positive values")
            continue
        edges = np.geomspace(pos.min(), pos.max() * (1 + 1e-9), 40)
        for c in classes:
            x = v[(df["label"] == c).to_numpy()]
            x = x[np.isfinite(x) & (x > 0)]
            if x.size:
                # fraction of the class's flows per log bin (density=True would favour narrow bins)
                ax.hist(x, bins=edges, weights=np.full(x.size, 1.0 / x.size), histtype="step", color=col[c], label=c)
        ax.set_xscale("log")
        ax.set_ylabel("fraction of flows")
        ax.set_title(f"{name} (flows with value > 0)")
    axes[0, 0].legend(fontsize=6, ncol=2)
    return save_png(fig, path)


def write_separability(out: str | Path, df: pd.DataFrame, stats: pd.DataFrame, emb: pd.DataFrame) -> list[Path]:
    """`uavcas analyze separability`'s files in `out`: separability.csv (`separability_stats`),
    tsne.csv (`tsne_embedding`), tsne.png and distributions.png (of the flows `df`)."""
    out = Path(out)
    return [atomic_write_text(out / "separability.csv", stats.to_csv(index=False)),
            atomic_write_text(out / "tsne.csv", emb.to_csv(index=False)),
            tsne_figure(emb, out / "tsne.png"), distributions_figure(df, out / "distributions.png")]
