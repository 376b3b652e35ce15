"""Feature distributions per class for the dataset report: box plots on a real log axis, every
class of the dataset in place, and the values a log axis cannot show counted instead of dropped.

A log axis has no 0 and no negative or non-finite value: those are counted per class ("12 of 40
zero") under the class's box and in a table, and a class whose values are all zero keeps its
place on the axis with no box. The axis is labelled with the column's unit from the data
dictionary; its ticks include 2 and 5 in each decade when the range is small, so counts such as
1, 2 and 5 SYNs stay readable.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.ticker import FuncFormatter, LogLocator

from uavcas.figure import plt, png_data_uri


def value_counts(values: np.ndarray) -> dict[str, int]:
    """rows, non-finite (NaN, +-inf), zero, negative and drawn (positive, finite) values."""
    finite = np.isfinite(values)
    return {"rows": int(values.shape[0]), "non-finite": int((~finite).sum()),
            "zero": int((values[finite] == 0).sum()), "negative": int((values[finite] < 0).sum()),
            "drawn": int((values[finite] > 0).sum())}


def _tick_label(cls: str, c: dict[str, int]) -> str:
    parts = [cls, f"{c['zero']} of {c['rows']} zero"]
    if c["non-finite"]:
        parts.append(f"{c['non-finite']} non-finite")
    if c["negative"]:
        parts.append(f"{c['negative']} negative")
    return "\n".join(parts)


def feature_figure(df: pd.DataFrame, feature: str, classes: list[str], unit: str) -> tuple[str, dict[str, dict]]:
    """The box plot of `feature` per class (data URI) and each class's counts."""
    counts, data = {}, []
    for c in classes:
        v = df.loc[df["label"] == c, feature].to_numpy(dtype=float)
        counts[c] = value_counts(v)
        data.append(v[np.isfinite(v) & (v > 0)])
    fig, ax = plt.subplots(figsize=(max(6.0, 0.62 * len(classes) + 2.0), 4.6), layout="constrained")
    pos = [i + 1 for i, d in enumerate(data) if d.shape[0]]
    if pos:
        bp = ax.boxplot([d for d in data if d.shape[0]], positions=pos, widths=0.6, showfliers=False)
        # the axis spans what is drawn (whisker ends), not the outliers the boxes leave out
        ends = np.concatenate([w.get_ydata() for w in bp["whiskers"]])
        lo, hi = float(ends[ends > 0].min()), float(ends.max())
        ax.set_yscale("log")
        ax.set_ylim(lo / 1.5, hi * 1.5)
        if np.log10(hi / lo) <= 4:  # few decades: label 1, 2, 5 of each
            ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(FuncFormatter(lambda y, _: f"{y:g}"))
    for i, d in enumerate(data):
        if not d.shape[0]:
            ax.text(i + 1, 0.5, "no positive\nvalue", ha="center", va="center", fontsize=7, color="0.4",
                    transform=ax.get_xaxis_transform())
    ax.set_xlim(0.4, len(classes) + 0.6)
    ax.set_xticks(range(1, len(classes) + 1), [_tick_label(c, counts[c]) for c in classes], fontsize=7.5,
                  rotation=30, ha="right", rotation_mode="anchor")
    ax.set_ylabel(f"{feature} ({unit}, log scale)")
    ax.set_title(f"{feature} per class: positive values (box: quartiles, whiskers: 1.5 IQR)", fontsize=10)
    ax.grid(axis="y", which="major", lw=0.4, alpha=0.5)
    return png_data_uri(fig), counts


def counts_frame(all_counts: dict[str, dict[str, dict]], classes: list[str]) -> pd.DataFrame:
    """class x feature: the values no box shows ("3 zero, 1 non-finite of 40"; "none of 40")."""
    rows = []
    for c in classes:
        row = {"class": c}
        for feat, per_class in all_counts.items():
            k = per_class[c]
            parts = [f"{k[w]} {w}" for w in ("zero", "non-finite", "negative") if k[w]]
            row[feat] = f"{', '.join(parts) or 'none'} of {k['rows']}"
        rows.append(row)
    return pd.DataFrame(rows)
