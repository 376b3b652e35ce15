"""`uavcas report DATASET_DIR --out DIR`: one self-contained HTML page about a dataset.

The page embeds every figure (base64 PNG, so it can be mailed or archived alone) and also links
the PNG files written beside it. Contents: the dataset card, class counts, counts per
configuration axis, the topology of every window of one example run, and per-class
distributions of the flow features an analyst looks at first.
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import numpy as np
import pandas as pd

from uavcas.atomic import atomic_write_text
from uavcas.schema import AXIS_COLUMNS, CLASSES

from .figure import plt, save_png

_DPI = 100

# Features shown per class: time structure, volume and size, the ones the paper's figures use.
SHOWN_FEATURES = ("Flow IAT Mean", "Flow Packets/s", "Flow Duration", "Packet Length Mean", "Total Fwd Packets", "SYN Flag Count")
# the same for a dataset of host-window rows (`--view window-host`: `uavcas.labels.episodes`)
SHOWN_EPISODE_FEATURES = ("packets_per_s", "bytes_per_s", "peers", "syn_in", "synack_out", "flows_in")


class ReportError(ValueError):
    pass


def _feature_figure(df: pd.DataFrame, out: Path, shown: tuple[str, ...]) -> list[Path]:
    classes = [c for c in CLASSES if c in set(df["label"])]
    paths = []
    for feat in shown:
        if feat not in df.columns:
            continue
        fig, ax = plt.subplots(figsize=(7, 3.6))
        data, names = [], []
        for c in classes:
            v = df.loc[df["label"] == c, feat].to_numpy(dtype=float)
            v = v[np.isfinite(v)]
            pos = v[v > 0]
            if len(pos):
                # log scale: zeros (e.g. the IAT of a one-packet flow) are counted, not drawn
                data.append(np.log10(pos))
                names.append(f"{c}\n(n={len(pos)}, {len(v) - len(pos)} zero)")
        if not data:
            plt.close(fig)
            continue
        ax.boxplot(data, showfliers=False)
        ax.set_xticks(range(1, len(names) + 1), names, fontsize=7, rotation=30)
        ax.set_ylabel(f"log10({feat})")
        ax.set_title(f"{feat} per class", fontsize=10)
        safe = feat.replace("/", "_per_").replace(" ", "_")
        paths.append(save_png(fig, out / f"feature_{safe}.png", dpi=_DPI))
    return paths


def _img(path: Path, out: Path) -> str:
    b64 = base64.b64encode(path.read_bytes()).decode()
    rel = html.escape(str(path.relative_to(out)))
    return f'<a href="{rel}"><img alt="{rel}" src="data:image/png;base64,{b64}" style="max-width:100%"></a>'


def _table(rows: list[tuple], header: tuple[str, ...]) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def write_report(dataset_dir: str | Path, out_dir: str | Path) -> Path:
    from uavcas.dataset.parquet import read_flows
    from uavcas.dataset.store import read_card
    from uavcas.twin.model import Plan

    from .topology import draw_plan_windows

    dataset_dir, out = Path(dataset_dir), Path(out_dir)
    card = read_card(dataset_dir)
    flows_path = dataset_dir / "flows.parquet"
    if not flows_path.exists():
        raise ReportError(f"{dataset_dir}: no flows.parquet")
    episodes = card.get("unit") == "host-window"
    shown, unit = (SHOWN_EPISODE_FEATURES, "rows") if episodes else (SHOWN_FEATURES, "flows")
    df = read_flows(flows_path, columns=["run_id", "label", *AXIS_COLUMNS, *shown])
    out.mkdir(parents=True, exist_ok=True)

    sections = [f"<h2>Dataset card</h2><pre>{html.escape(json.dumps({k: v for k, v in card.items() if k != 'runs'}, indent=1))}</pre>"]
    counts = df["label"].value_counts()
    sections.append("<h2>Classes</h2>" + _table([(c, int(counts.get(c, 0))) for c in CLASSES if counts.get(c, 0)], ("class", unit)))
    axis_html = []
    for ax in AXIS_COLUMNS:
        vc = df.groupby(ax, observed=True).agg(n=("label", "size"), runs=("run_id", "nunique")).reset_index()
        if len(vc) > 1 or ax in ("attacks", "mission", "pathloss", "n_uav", "tx_dbm"):
            axis_html.append(f"<h3>{html.escape(ax)}</h3>" + _table([tuple(r) for r in vc.itertuples(index=False)], (ax, unit, "runs")))
    sections.append("<h2>Configuration axes</h2>" + "".join(axis_html))

    example = None
    for plan_path in sorted((dataset_dir / "runs").glob("*/plan.json"), key=lambda p: int(p.parent.name) if p.parent.name.isdigit() else 0):
        plan = Plan.from_json(plan_path.read_text())
        if plan.attacks or example is None:
            example = (plan_path.parent.name, plan)
        if plan.attacks:
            break
    if example is not None:
        run_id, plan = example
        figs = draw_plan_windows(plan, out / "topology")
        sections.append(
            f"<h2>Example topology: run {html.escape(run_id)}</h2><p><code>{html.escape(plan.config)}</code> seed {plan.seed}</p>"
            + "".join(_img(p, out) for p in figs)
        )
    from .fidelity import fidelity_section

    sections.append(fidelity_section(dataset_dir, out, card))
    feat_figs = _feature_figure(df, out, shown)
    title = "Host-window features per class" if episodes else "Flow features per class"
    sections.append(f"<h2>{title}</h2>" + "".join(_img(p, out) for p in feat_figs))
    links = "".join(f'<li><a href="{html.escape(str(p.relative_to(out)))}">{html.escape(p.name)}</a></li>' for p in sorted(out.rglob("*.png")))
    sections.append(f"<h2>Figures</h2><ul>{links}</ul>")
    page = (
        "<!doctype html><html><head><meta charset='utf-8'><title>uavcas dataset report</title>"
        "<style>body{font-family:sans-serif;max-width:1100px;margin:auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}</style></head><body>"
        f"<h1>uavcas dataset: {html.escape(str(dataset_dir))}</h1>" + "".join(sections) + "</body></html>\n"
    )
    index = out / "index.html"
    atomic_write_text(index, page)
    return index
