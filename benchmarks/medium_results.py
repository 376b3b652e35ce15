"""docs/results.md and docs/results/medium-leaderboard.csv, written whole from the medium campaign.

usage (the commands that make every input are in the page's "Regenerate" section):

    python benchmarks/medium_results.py --campaign data/medium \\
        --dataset 5tuple=data/medium --dataset window-host=data/medium-wh \\
        --bench 5tuple=bench/5tuple --bench 5tuple=bench/5tuple-cross \\
        --bench window-host=bench/wh --bench window-host=bench/wh-cross \\
        --previous docs/results/medium-leaderboard-v0.2.csv \\
        --torch docs/results/torch-devices-h200.json --out docs

Every number on the page is computed here from those inputs: the campaign's run directories
(outcome.json, fidelity.json), the two datasets (labels and run ids), the `bench ids` outputs
(leaderboard.csv, and per protocol results.csv / results.json), the previous release's
leaderboard and the GPU timing file. The prose around the numbers is fixed text. The paper's
values (its Tables 'tab:baseline_f1', 'tab:per_attack', 'tab:collab_f1', percent) are constants
copied here as published and shown in brackets.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd

from uavcas.ids.detectors import baselines, detectors, names

# display names, from the detector registry: the paper's ten baselines, then the context detectors
MODELS = [s.display for s in baselines()]
CONTEXT = [s.display for s in detectors() if s.uses_context]
VIEWS = {"5tuple": "5-tuple flows", "window-host": "window-host episodes"}
PROTOCOLS = ["binary", "multiclass", "ood", "cross-condition"]
# paper, binary Benign-vs-DoS weighted F1 (%) on UAV-CAS
PAPER_BINARY = {"1D-CNN": 99.98, "LSTM": 98.86, "RF": 99.99, "SGD": 99.98, "LR": 99.99, "MLP": 99.98,
                "LightGBM": 99.96, "ConvNet": 99.99, "TinyML": 99.98, "CNN-BiLSTM": 99.99}
PAPER_CLASSES = ["Benign", "DoS", "DDoS", "Blackhole", "Wormhole", "Replay", "Blackhole+DoS", "Blackhole+DDoS",
                 "Blackhole+Replay", "Blackhole+Wormhole", "DDoS+Replay", "DDoS+Wormhole", "DoS+Replay",
                 "DoS+Wormhole", "Replay+Wormhole"]
NEW_FAMILY_CLASSES = ["GPSSpoofing", "Jamming", "MAVLinkInjection"]
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
# the targets (issue 25, "Done when")
MIN_ROWS, MIN_RUNS = 30, 2
STEALTH_MARGIN, MIN_SEEDS_WON, WORMHOLE_F1, BINARY_F1 = 0.10, 4, 0.30, 0.98


# --- inputs -------------------------------------------------------------------------------------
def _pairs(items: list[str], flag: str) -> list[tuple[str, Path]]:
    out = []
    for it in items:
        view, sep, path = it.partition("=")
        if not sep or view not in VIEWS:
            raise SystemExit(f"{flag} {it!r}: expected VIEW=PATH with VIEW one of {', '.join(VIEWS)}")
        out.append((view, Path(path)))
    return out


def read_benches(benches: list[tuple[str, Path]]) -> tuple[pd.DataFrame, pd.DataFrame, list[dict]]:
    """(summary rows with a view column, per-seed rows with a view column, each protocol's results.json);
    where two outputs hold the same view, protocol and model, the later one's rows are kept."""
    lbs, seeds, metas = [], [], []
    for view, d in benches:
        lb = pd.read_csv(d / "leaderboard.csv", keep_default_na=False, na_values=[""])
        lbs.append(lb.assign(view=view))
        for rj in sorted(d.rglob("results.json")):
            meta = json.loads(rj.read_text())
            metas.append({**meta, "view": view})
            rs = pd.read_csv(rj.parent / "results.csv", keep_default_na=False, na_values=[""])
            seeds.append(rs.assign(view=view))
    # a later --bench of the same view and protocol replaces the models it holds (a re-run of
    # some models, e.g. the context detector after a change that leaves the baselines' code alone)
    lb = pd.concat(lbs, ignore_index=True).drop_duplicates(["view", "protocol", "model", "metric", "class"],
                                                           keep="last")
    seeds = pd.concat(seeds, ignore_index=True).drop_duplicates(
        ["view", "protocol", "seed", "model", "metric", "class"], keep="last")
    return lb, seeds, metas


def read_campaign(root: Path) -> pd.DataFrame:
    """One row per manifest entry: config, DONE, wall_s, fidelity verdict, failed checks, delay error quantiles."""
    rows = []
    for line in (root / "campaign.jsonl").read_text().splitlines():
        e = json.loads(line)
        run = root / "runs" / str(e["index"])
        row = {"index": e["index"], "config": e["config"], "done": (run / "DONE").exists()}
        if (run / "outcome.json").exists():
            row["wall_s"] = json.loads((run / "outcome.json").read_text()).get("wall_s")
        if (run / "fidelity.json").exists():
            f = json.loads((run / "fidelity.json").read_text())
            row.update(verdict=f.get("verdict"), failed=",".join(f.get("failed", [])),
                       **{k: f.get(k) for k in ("delay_error_p50_ms", "delay_error_p90_ms", "delay_error_p99_ms")})
        rows.append(row)
    return pd.DataFrame(rows)


def read_classes(path: Path) -> pd.DataFrame:
    """Per class: rows, runs holding it, median packets per row."""
    df = pd.read_parquet(path / "flows.parquet", columns=["run_id", "label", "packets"])
    g = df.groupby("label")
    return pd.DataFrame({"rows": g.size(), "runs": g["run_id"].nunique(), "median_packets": g["packets"].median()})


# --- formatting ---------------------------------------------------------------------------------
def pct(row: pd.Series | None, digits: int = 1) -> str:
    if row is None or pd.isna(row["mean"]):
        return "-"
    return f"{row['mean'] * 100:.{digits}f} ± {row['std'] * 100:.{digits}f}"


def secs(row: pd.Series | None) -> str:
    return "-" if row is None or pd.isna(row["mean"]) else f"{row['mean']:.1f} ± {row['std']:.1f}"


def get(lb: pd.DataFrame, view: str, protocol: str, model: str, metric: str, cls: str = "") -> pd.Series | None:
    m = lb[(lb.view == view) & (lb.protocol == protocol) & (lb.model == model) & (lb.metric == metric)
           & (lb["class"].fillna("") == cls)]
    return None if m.empty else m.iloc[0]


def table(head: list[str], rows: list[list[str]]) -> list[str]:
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head), *("| " + " | ".join(r) + " |" for r in rows), ""]


def models_in(lb: pd.DataFrame, view: str, protocol: str) -> list[str]:
    have = set(lb[(lb.view == view) & (lb.protocol == protocol)].model)
    return [m for m in MODELS + CONTEXT if m in have]


def declared(metas: list[dict], view: str, protocol: str) -> list[str]:
    for m in metas:
        if m["view"] == view and m["protocol"] == protocol:
            return list(m["declared"])
    return []


def class_order(classes: list[str]) -> list[str]:
    from uavcas.vocabulary import CLASSES

    known = [c for c in CLASSES if c in classes]
    return known + sorted(c for c in classes if c not in known)


# --- the checks of the issue ----------------------------------------------------------------------
def seed_margins(seeds: pd.DataFrame, view: str) -> pd.DataFrame:
    """Per seed of the multiclass protocol: Context's stealth macro-F1, the best baseline's and the margin."""
    s = seeds[(seeds.view == view) & (seeds.protocol == "multiclass") & (seeds.metric == "f1_macro")
              & (seeds["class"].fillna("") == "stealth")]
    out = []
    for seed, g in s.groupby("seed"):
        base = g[g.model.isin(MODELS)]
        ctx = g[g.model == "Context"]
        if base.empty or ctx.empty:
            continue
        best = base.loc[base.value.idxmax()]
        out.append({"seed": int(seed), "context": float(ctx.value.iloc[0]), "best": float(best.value),
                    "best_model": best.model, "margin": float(ctx.value.iloc[0]) - float(best.value)})
    return pd.DataFrame(out)


def rows_runs(c: pd.DataFrame, cls: str) -> tuple[int, int]:
    """A class's rows and the runs holding them in one view's class table (0, 0 where absent)."""
    return (int(c.loc[cls, "rows"]), int(c.loc[cls, "runs"])) if cls in c.index else (0, 0)


def at_bar(rows: int, runs: int) -> bool:
    """The issue's bar for a class: >= MIN_ROWS rows from >= MIN_RUNS runs."""
    return rows >= MIN_ROWS and runs >= MIN_RUNS


def checks(lb: pd.DataFrame, seeds: pd.DataFrame, classes: dict[str, pd.DataFrame]) -> list[list[str]]:
    rows = []
    if "window-host" in classes:
        c = classes["window-host"]
        for cls in PAPER_CLASSES + NEW_FAMILY_CLASSES:
            n, r = rows_runs(c, cls)
            ok = at_bar(n, r)
            rows.append([f"window-host rows of {cls} (>= {MIN_ROWS} from >= {MIN_RUNS} runs)", f"{n} rows, {r} runs",
                         "met" if ok else "**not met**"])
    for view in VIEWS:
        if lb.empty or not (lb["view"] == view).any():
            rows.append([f"{view}: the context targets", "no `bench ids` output of this view among the inputs",
                         "**not measured**"])
            continue
        m = seed_margins(seeds, view)
        if get(lb, view, "multiclass", "Context", "f1_macro", "stealth") is None:  # the targets it would measure
            rows.append([f"{view}: Context stealth macro-F1 and Wormhole F1", "no multiclass output of this view "
                         "among the inputs", "**not measured**"])
        if not m.empty:
            won = int((m.margin >= STEALTH_MARGIN).sum())
            rows.append([f"{view}: Context stealth macro-F1 >= best baseline + {STEALTH_MARGIN:.2f} on >= "
                         f"{MIN_SEEDS_WON} of 5 seeds", f"{won} of {len(m)} seeds (margins "
                         + ", ".join(f"{x * 100:+.1f}" for x in m.margin) + " points)",
                         "met" if won >= MIN_SEEDS_WON else "**not met**"])
        w = get(lb, view, "multiclass", "Context", "f1", "Wormhole")
        if w is not None:
            rows.append([f"{view}: Context Wormhole F1 >= {WORMHOLE_F1:.2f}", f"{w['mean']:.3f} ± {w['std']:.3f}",
                         "met" if w["mean"] >= WORMHOLE_F1 else "**not met**"])
        b = get(lb, view, "binary", "Context", "f1_weighted")
        if b is not None:
            rows.append([f"{view}: Context binary weighted F1 >= {BINARY_F1:.2f}", f"{b['mean']:.4f} ± {b['std']:.4f}",
                         "met" if b["mean"] >= BINARY_F1 else "**not met**"])
    return rows


# --- sections -------------------------------------------------------------------------------------
def campaign_section(camp: pd.DataFrame) -> list[str]:
    done = camp[camp.done]
    audited = done.dropna(subset=["verdict"])
    passed = int((audited.verdict == "pass").sum())
    out = ["## The campaign", "",
           f"{len(camp)} runs in the manifest, {len(done)} done. Wall time per run (realisation, audit and extraction "
           f"of one run, `outcome.json`): median {done.wall_s.median():.0f} s, sum {done.wall_s.sum() / 3600:.2f} h.",
           "",
           f"**Fidelity audit**: {passed} of {len(audited)} runs pass. Per-hop delay error over the runs (median of "
           f"the runs' p50 / p90 / p99): {audited.delay_error_p50_ms.median():.3f} / "
           f"{audited.delay_error_p90_ms.median():.3f} / {audited.delay_error_p99_ms.median():.3f} ms; largest p99 "
           f"{audited.delay_error_p99_ms.max():.2f} ms. Runs kept and flagged (`dataset.json`), with the checks "
           "they failed:", ""]
    flagged = audited[audited.verdict != "pass"].sort_values("index")
    out += table(["run", "scenario", "failed checks", "p99 delay error ms"],
                 [[str(r["index"]), f"`{r.config}`", r.failed or "-", f"{r.delay_error_p99_ms:.2f}"]
                  for _, r in flagged.iterrows()]) if len(flagged) else ["(none)", ""]
    return out


def classes_section(classes: dict[str, pd.DataFrame]) -> list[str]:
    names = class_order(sorted(set().union(*(set(c.index) for c in classes.values()))))
    head = ["class"] + [h for v in classes for h in (f"{v}: rows", f"{v}: runs", f"{v}: median packets")]
    rows = []
    for cls in names:
        cells = [cls]
        for c in classes.values():
            cells += ([f"{int(c.loc[cls, 'rows']):,}", str(int(c.loc[cls, "runs"])),
                       f"{c.loc[cls, 'median_packets']:g}"]
                      if cls in c.index else ["0", "0", "-"])
        rows.append(cells)
    return ["## Classes per view", "",
            "A 5-tuple row is one flow (one TCP connection, trailing packets joined); a window-host row is one "
            "node in one plan window, the unit where both attacks of a composition meet on the victim. Labels "
            "come from each packet's one effect in both views.", "", *table(head, rows)]


def binary_section(lb: pd.DataFrame, view: str) -> list[str]:
    models = models_in(lb, view, "binary")
    if not models:
        return []
    rows = [[m, str(PAPER_BINARY.get(m, "-")) if view == "5tuple" else "-",
             pct(get(lb, view, "binary", m, "f1_weighted"), 2),
             pct(get(lb, view, "binary", m, "auroc"), 2), secs(get(lb, view, "binary", m, "fit_s"))] for m in models]
    return [f"### Binary (Benign vs DoS), weighted F1 % — {VIEWS[view]}", "",
            *table(["model", "paper", "ours", "AUROC %", "fit s"], rows)]


def multiclass_section(lb: pd.DataFrame, metas: list[dict], view: str) -> list[str]:
    models = models_in(lb, view, "multiclass")
    if not models:
        return []
    classes = class_order(declared(metas, view, "multiclass"))
    rows = []
    for m in models:
        cells = [m]
        for c in classes:
            ours = pct(get(lb, view, "multiclass", m, "f1", c))
            known = view == "5tuple" and m in PAPER_PER_CLASS and c in PAPER_CLASSES
            paper = PAPER_PER_CLASS[m][PAPER_CLASSES.index(c)] if known else None
            cells.append(ours + (f" [{paper}]" if paper is not None else ""))
        cells += [pct(get(lb, view, "multiclass", m, "f1_macro")),
                  pct(get(lb, view, "multiclass", m, "f1_macro", "stealth")),
                  secs(get(lb, view, "multiclass", m, "fit_s"))]
        rows.append(cells)
    return [f"### Multiclass, per-class F1 % — {VIEWS[view]}"
            + (" (the paper's in brackets)" if view == "5tuple" else ""), "",
            f"{len(classes)} declared classes (every class held by enough runs for a grouped split).", "",
            *table(["model", *classes, "macro", "stealth", "fit s"], rows)]


def ood_section(lb: pd.DataFrame, view: str) -> list[str]:
    models = models_in(lb, view, "ood")
    od = lb[(lb.view == view) & (lb.protocol == "ood") & (lb.metric == "auroc")]
    comps = class_order(sorted(set(od["class"].dropna()) - {""}))
    if not models or not comps:
        return []
    rows = []
    for c in comps:
        cells = [c]
        for m in models:
            paper = PAPER_OOD[c][MODELS.index(m)] if view == "5tuple" and c in PAPER_OOD and m in MODELS else None
            cells.append(pct(get(lb, view, "ood", m, "auroc", c)) + (f" [{paper}]" if paper is not None else ""))
        rows.append(cells)
    return [f"### OOD: trained on benign and single attacks, AUROC % per unseen composition — {VIEWS[view]}", "",
            *table(["composition", *models], rows)]


def cross_section(lb: pd.DataFrame, view: str) -> list[str]:
    models = models_in(lb, view, "cross-condition")
    if not models:
        return []
    rows = [[m, pct(get(lb, view, "cross-condition", m, "f1_weighted")),
             pct(get(lb, view, "cross-condition", m, "f1_macro")),
             pct(get(lb, view, "cross-condition", m, "f1_macro", "stealth")),
             pct(get(lb, view, "cross-condition", m, "f1_macro_iid"))] for m in models]
    return [f"### Cross-condition: one channel setting never trained on, % — {VIEWS[view]}", "",
            *table(["model", "weighted F1 held-out", "macro F1 held-out", "stealth macro F1 held-out",
                    "macro F1 seen settings"], rows)]


def context_section(lb: pd.DataFrame, seeds: pd.DataFrame, view: str) -> list[str]:
    stealth = {m: get(lb, view, "multiclass", m, "f1_macro", "stealth") for m in MODELS}
    have = [m for m in MODELS if stealth[m] is not None]
    if not have:
        return []
    best = max(have, key=lambda m: stealth[m]["mean"])
    cols = [("f1_macro", "stealth"), ("f1_macro", ""), ("f1", "Blackhole"), ("f1", "Wormhole"), ("f1", "Replay"),
            ("f1", "DoS"), ("f1", "DDoS")]
    rows = [[f"{m} (best baseline)" if m == best else m, *(pct(get(lb, view, "multiclass", m, a, c)) for a, c in cols),
             pct(get(lb, view, "binary", m, "f1_weighted"), 2)]
            for m in [x for x in CONTEXT if get(lb, view, "multiclass", x, "f1_macro") is not None] + [best]]
    out = [f"### Context detector and its ablation beside the best baseline — {VIEWS[view]}", "",
           *table(["model", "stealth macro-F1", "macro-F1", "Blackhole", "Wormhole", "Replay", "DoS", "DDoS",
                   "binary weighted F1"], rows)]
    m = seed_margins(seeds, view)
    if not m.empty:
        out += ["Per seed, Context against the best of the ten baselines of that seed (stealth macro-F1 %):", "",
                *table(["seed", "Context", "best baseline", "which", "margin (points)"],
                       [[str(r.seed), f"{r.context * 100:.1f}", f"{r.best * 100:.1f}", r.best_model,
                         f"{r.margin * 100:+.1f}"] for r in m.itertuples()])]
    return out


def fit_section(lb: pd.DataFrame, metas: list[dict]) -> list[str]:
    out = ["## Fit time per model, s (mean ± std over seeds)", ""]
    devices = sorted({f.get("device", "cpu") for meta in metas for f in meta.get("fits", [])})
    for view in VIEWS:
        models = sorted({m for p in PROTOCOLS for m in models_in(lb, view, p)}, key=(MODELS + CONTEXT).index)
        if models:
            out += [f"{VIEWS[view]}:", "", *table(["model", *PROTOCOLS],
                                                 [[m, *(secs(get(lb, view, p, m, "fit_s")) for p in PROTOCOLS)]
                                                  for m in models])]
    out += [f"Devices the fits ran on (`results.json` of each protocol): {', '.join(devices) or '-'}.", ""]
    return out


def torch_section(path: Path | None) -> list[str]:
    if path is None or not path.exists():
        return []
    d = json.loads(path.read_text())
    f = pd.DataFrame(d["fits"])
    t = f.groupby(["model", "resolved"])["fit_s"].sum().unstack()
    rows = [[m, f"{t.loc[m, 'cuda']:.1f}", f"{t.loc[m, 'cpu']:.1f}", f"{t.loc[m, 'cpu'] / t.loc[m, 'cuda']:.1f}x"]
            for m in t.index]
    rows.append(["all five", f"{t['cuda'].sum():.1f}", f"{t['cpu'].sum():.1f}",
                 f"{t['cpu'].sum() / t['cuda'].sum():.1f}x"])
    return ["## The torch baselines on a GPU", "",
            f"`benchmarks/torch_devices.py` on one {d['gpu']} against {d['cpu_threads']} CPU threads of the same "
            f"machine (torch {d['torch']}): protocol {d['protocol']}, seeds {', '.join(map(str, d['seeds']))}, at most "
            f"{d['epochs']} epochs and {d['train_cap']} training rows per run and class, on `{d['dataset']}` "
            f"({d['flows']:,} flows of the medium design, `uavcas dataset synth`; not this campaign). Fit seconds "
            "summed over the seeds:", "", *table(["model", "CUDA s", "CPU s", "CPU / CUDA"], rows)]


def changes_section(lb: pd.DataFrame, previous: Path | None, classes: dict[str, pd.DataFrame]) -> list[str]:
    out = ["## What changed against the previous results, and why", ""]
    if previous is not None and previous.exists():
        prev = pd.read_csv(previous, keep_default_na=False, na_values=[""]).assign(view="5tuple")
        cols = [("multiclass", "f1_macro", "stealth", "stealth macro-F1"), ("multiclass", "f1_macro", "", "macro-F1"),
                ("multiclass", "f1", "Benign", "Benign F1"), ("multiclass", "f1", "Wormhole", "Wormhole F1"),
                ("binary", "f1_weighted", "", "binary weighted F1")]
        rows = []
        for m in MODELS + CONTEXT:
            cells = [m]
            for p, metric, c, _ in cols:
                a, b = get(prev, "5tuple", p, m, metric, c), get(lb, "5tuple", p, m, metric, c)
                cells.append(f"{pct(a)} -> {pct(b)}")
            rows.append(cells)
        out += [f"5-tuple view, previous release (`{previous.name}`, 64 runs of image traffic) -> now, %:", "",
                *table(["model", *(h for *_, h in cols)], rows)]
    if "5tuple" in classes and "Benign" in classes["5tuple"].index:
        b = classes["5tuple"].loc["Benign"]
        out += [f"Benign flows now: {int(b['rows']):,} in {int(b['runs'])} runs, median {b['median_packets']:g} "
                "packets.", ""]
    out += [
        "- **Benign is traffic no attack touched.** Before, a flood victim's SYN-ACK retransmissions were split "
        "off into flows of their own by a RST rule and most of them were labelled Benign; now a packet an "
        "attack provoked carries that attack's family (effect `provoked`), and one TCP connection is one flow.",
        "- **No TCP appendices.** Lone ACKs after a first-FIN cut (CICFlowMeter's behaviour, the CICIDS2017 "
        "artifact) no longer form flows; `--termination cic` keeps that behaviour as an option.",
        "- **UAV traffic.** Payload `mixed`: MAVLink 2 telemetry and commands (pymavlink endpoints), H.264 video "
        "(ffmpeg) and image fetches, where the previous campaign had image fetches only; stealth attacks now "
        "act on long streams, which is why the context columns look at every window a stream crosses.",
        "- **Three attack rounds per run.** Each run repeats its composition on three victims, so that every "
        "collaborative class has victims in enough windows for the window-host view; and the new families "
        "(jamming, GPS spoofing, MAVLink injection) enter with their compositions.",
        *composition_bullet(classes), ""]
    return out


def composition_bullet(classes: dict[str, pd.DataFrame]) -> list[str]:
    """How many of the paper's compositions each view holds at the issue's bar (>= MIN_ROWS rows from >= MIN_RUNS
    runs), counted from the class tables, since a 5-tuple flow holds two attacks' effects only where both
    reach one connection (a flood's flows that a wormhole detours, a replayed session that a blackhole drops)."""
    comps = [c for c in PAPER_CLASSES if "+" in c]
    counts = "; ".join(f"{VIEWS[v]}: {sum(at_bar(*rows_runs(c, x)) for x in comps)}" for v, c in classes.items())
    return [f"- **The window-host view** is new: it is where both attacks of a composition meet, on the victim in a "
            f"window. Of the paper's {len(comps)} compositions, those holding >= {MIN_ROWS} rows from >= {MIN_RUNS} "
            f"runs: {counts}. A 5-tuple flow holds two attacks' effects only where both reach one connection."]


def regenerate_section(camp: pd.DataFrame) -> list[str]:
    settings = sorted({"-".join(c.split("-")[-8:]) for c in camp.config})
    return ["## Regenerate", "",
            "```bash",
            f"# {len(camp)} runs: the medium preset (root; resumable: re-running the command resumes it)",
            ".venv/bin/uavcas campaign run --preset medium --out data/medium",
            "# the same runs as window-host episodes",
            "for r in data/medium/runs/*/; do .venv/bin/uavcas extract \"$r\" --view window-host --out data/medium-wh; "
            "done",
            f"M={','.join(names())}",  # every registered detector
            "B=\"--seeds 0,1,2,3,4 --models $M --train-cap 300 --epochs 15 --no-importance\"",
            "for v in medium:5tuple medium-wh:wh; do",
            "  .venv/bin/uavcas bench ids data/${v%%:*} --out bench/${v##*:} --protocol binary,multiclass,ood "
            "--min-class-runs 2 $B",
            "  .venv/bin/uavcas bench ids data/${v%%:*} --out bench/${v##*:}-cross --protocol cross-condition \\",
            "      --holdout mission=spiral --min-class-runs 3 $B",
            "done",
            ".venv/bin/python benchmarks/medium_results.py --campaign data/medium --dataset 5tuple=data/medium \\",
            "    --dataset window-host=data/medium-wh --bench 5tuple=bench/5tuple --bench 5tuple=bench/5tuple-cross \\",
            "    --bench window-host=bench/wh --bench window-host=bench/wh-cross \\",
            "    --previous docs/results/medium-leaderboard-v0.2.csv --torch docs/results/torch-devices-h200.json "
            "--out docs",
            "```", "",
            "Channel settings (UAVs, base stations, payload, path loss, MCS, mission, TX dBm, noise): "
            + ", ".join(f"`{s}`" for s in settings) + ". Runs are real-time emulations, so row counts move a little "
            "between regenerations (a flood's packets per window depend on the host's scheduling); plans, splits "
            "and model seeds do not.", ""]


def page(camp, classes, lb, seeds, metas, previous, torch_json) -> str:
    out = ["# Results on the medium campaign", "",
           "<!-- generated by benchmarks/medium_results.py: do not edit; every number below comes from the inputs "
           "named in its docstring -->", "",
           "What the ten baselines and the context-aware detector score on a real `medium` campaign, in two views of "
           "the same runs, beside the paper's tables. Scores are mean ± std over five grouped seeds (splits by run); "
           "`docs/results/medium-leaderboard.csv` holds every one (view, protocol, model, metric, class, mean, std; "
           "class `stealth`: the macro-F1 over the classes holding a blackhole, replay or wormhole).", ""]
    out += regenerate_section(camp) + campaign_section(camp) + classes_section(classes)
    out += ["## The targets of this release", "", *table(["target", "measured", ""], checks(lb, seeds, classes))]
    for view in VIEWS:
        body = (binary_section(lb, view) + multiclass_section(lb, metas, view) + ood_section(lb, view)
                + cross_section(lb, view) + context_section(lb, seeds, view))
        if body:
            out += [f"## {VIEWS[view].capitalize()}", "", *body]
        else:
            out += [f"## {VIEWS[view].capitalize()}", "",
                    "Not benchmarked in this version: the inputs name no `bench ids` output of this view.", ""]
    out += fit_section(lb, metas) + torch_section(torch_json) + changes_section(lb, previous, classes)
    return "\n".join(out).rstrip() + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--campaign", type=Path, required=True)
    ap.add_argument("--dataset", action="append", default=[], help="VIEW=DATASET_DIR")
    ap.add_argument("--bench", action="append", default=[], help="VIEW=BENCH_DIR (a `bench ids` --out)")
    ap.add_argument("--previous", type=Path)
    ap.add_argument("--torch", type=Path)
    ap.add_argument("--out", type=Path, required=True,
                    help="docs directory: results.md and results/medium-leaderboard.csv")
    a = ap.parse_args()
    camp = read_campaign(a.campaign)
    classes = {v: read_classes(p) for v, p in _pairs(a.dataset, "--dataset")}
    lb, seeds, metas = read_benches(_pairs(a.bench, "--bench"))
    (a.out / "results").mkdir(parents=True, exist_ok=True)
    cols = ["view", "protocol", "model", "metric", "class", "mean", "std"]
    lb[cols].sort_values(cols[:5], kind="stable").to_csv(a.out / "results" / "medium-leaderboard.csv", index=False)
    (a.out / "results.md").write_text(page(camp, classes, lb, seeds, metas, a.previous, a.torch))
    print(a.out / "results.md", len(lb), "leaderboard rows")


if __name__ == "__main__":
    main()
