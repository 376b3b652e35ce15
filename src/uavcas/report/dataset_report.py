"""`uavcas report DATASET_DIR --out DIR`: one self-contained HTML page about a dataset, DIR/index.html.

The page is rendered from a jinja2 template (`templates/report.html.j2`, package data) with tables
from pandas' Styler; every figure is inlined as a base64 PNG, with no link to any other file, no
script and nothing fetched from a network, so index.html alone can be mailed or archived. In
order: a summary (runs, rows per class and view, fidelity verdicts, the labelling and flow
termination policies), one row per run (scenario, seed, classes, verdict with the failed check,
links to its details), the topology of each attack run at each attack's start, fidelity per run
with every column explained, feature distributions per class, and the card's JSON (collapsed).
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import jinja2
import pandas as pd
import pyarrow.parquet as pq

from uavcas.atomic import atomic_write_text
from uavcas.dataset.dictionary import describe
from uavcas.dataset.parquet import read_flows
from uavcas.dataset.runs import class_table, dataset_runs
from uavcas.dataset.store import card_standard, read_card
from uavcas.figure import png_data_uri
from uavcas.labels.label import rule_summary
from uavcas.schema import CLASSES
from uavcas.twin.load import read_plan
from uavcas.views import ViewSpec, card_view

from .distributions import counts_frame, feature_figure
from .fidelity import COLUMNS as FIDELITY_HELP
from .fidelity import fidelity_figure, fidelity_frame, read_run_fidelity
from .topology import attack_start_figure

TEMPLATE = "report.html.j2"


class ReportError(ValueError):
    pass


def _styled(df: pd.DataFrame, raw: tuple[str, ...] = ()) -> str:
    """HTML of a table (pandas Styler): cells escaped, except the `raw` columns (links we built)."""
    text = [c for c in df.columns if c not in raw]
    sty = df.style.hide(axis="index").format(escape="html", subset=text, na_rep="", precision=3)
    numeric = [c for c in df.columns if pd.api.types.is_numeric_dtype(df[c])]
    if numeric:
        sty = sty.set_properties(subset=numeric, **{"text-align": "right"})
    return f'<div class="wide">{sty.to_html()}</div>'  # a table wider than the page scrolls


def _class_table(df: pd.DataFrame) -> str:
    return _styled(class_table(df))


def _summary(card: dict, df: pd.DataFrame, runs, standard: str, view: ViewSpec) -> dict:
    rules = card.get("runs") or []
    flow_rules = sorted({json.dumps(r.get("flow_rules") or {}, sort_keys=True) for r in rules} - {"{}"})
    headlines, parts = rule_summary(card.get("label_rules", []))
    return {
        "rows": len(df), "unit": view.row.singular,
        "runs": card.get("n_runs", len(runs)), "standard": standard,
        "fidelity": card.get("fidelity") or {"unaudited": len(runs)}, "flagged": sum(r.flagged for r in runs),
        "class_table": _class_table(df), "label_modes": card.get("label_modes", []),
        # each rule's first sentence (the policy), then every family's rule
        "label_headlines": headlines, "label_rules": parts, "terminations": card.get("terminations", []),
        "flow_rules": flow_rules,
    }


def _runs_table(runs, topo_ids: set[str], fid_ids: set[str], unit: str) -> str:
    rows = []
    for r in runs:
        links = [f'<a href="#run-{html.escape(r.run_id)}">topology</a>'] if r.run_id in topo_ids else []
        links += [f'<a href="#fidelity-{html.escape(r.run_id)}">fidelity</a>'] if r.run_id in fid_ids else []
        rows.append({"run": r.run_id, "config": r.config, "seed": "" if r.seed is None else str(r.seed),
                     f"{unit}s": r.rows, "classes": ", ".join(f"{c} {n}" for c, n in r.classes.items()),
                     "fidelity": r.verdict + (f": {'; '.join(r.failed)}" if r.failed else ""),
                     "details": " ".join(links) or "-"})
    return _styled(pd.DataFrame(rows), raw=("details",))


def _topologies(dataset_dir: Path, runs) -> list[dict]:

    out = []
    for r in runs:
        path = dataset_dir / "runs" / r.run_id / "plan.json"
        if not path.is_file():
            continue
        try:
            plan = read_plan(path.read_text())
        except ValueError:
            continue  # an unreadable plan: the run is listed without a figure
        fig = attack_start_figure(plan)
        if fig is not None:
            out.append({"run_id": r.run_id, "config": plan.config, "seed": plan.seed, "uri": png_data_uri(fig, dpi=90)})
    return out


def _fidelity(dataset_dir: Path, runs) -> tuple[str | None, str | None]:
    audits = read_run_fidelity(dataset_dir)
    if not audits:
        return None, None
    by_id = {r.run_id: r for r in runs}
    frame = fidelity_frame(audits, {k: r.config for k, r in by_id.items()},
                           {k: "; ".join(r.failed) for k, r in by_id.items()})
    # each row an anchor (#fidelity-<run>) the run table links to
    frame["run"] = [f'<a id="fidelity-{html.escape(str(rid))}"></a>{html.escape(str(rid))}' for rid in frame["run"]]
    table = _styled(frame, raw=("run",))
    return table, fidelity_figure(audits)


def _distributions(df: pd.DataFrame, standard: str, view: ViewSpec) -> dict:
    classes = [c for c in CLASSES if c in set(df["label"])] + sorted(set(df["label"]) - set(CLASSES))
    figures, counts = [], {}
    for feat in view.shown_features:
        if feat in df.columns:
            uri, counts[feat] = feature_figure(df, feat, classes, describe(feat, standard, view)[0])
            figures.append({"feature": feat, "uri": uri})
    return {"title": view.report_title, "figures": figures,
            "counts_table": _styled(counts_frame(counts, classes)) if counts else ""}


def write_report(dataset_dir: str | Path, out_dir: str | Path) -> Path:
    """Render DATASET_DIR's report into OUT_DIR/index.html (the only file written); returns its path."""
    dataset_dir, out = Path(dataset_dir), Path(out_dir)
    card = read_card(dataset_dir)
    flows_path = dataset_dir / "flows.parquet"
    if not flows_path.exists():
        raise ReportError(f"{dataset_dir}: no flows.parquet")
    view = card_view(card)
    standard = card_standard(card)
    names = set(pq.read_schema(flows_path).names)
    df = read_flows(flows_path, columns=[c for c in ("run_id", "label", "view", *view.shown_features) if c in names])
    runs = dataset_runs(dataset_dir, card)
    summary = _summary(card, df, runs, standard, view)
    topologies = _topologies(dataset_dir, runs)
    fid_table, fid_uri = _fidelity(dataset_dir, runs)

    fid_ids = {r.run_id for r in runs if (dataset_dir / "runs" / r.run_id / "fidelity.json").is_file()}
    card_json = json.dumps(card, indent=1)
    env = jinja2.Environment(loader=jinja2.PackageLoader("uavcas.report", "templates"),
                             autoescape=jinja2.select_autoescape(["html", "j2"]), undefined=jinja2.StrictUndefined)
    page = env.get_template(TEMPLATE).render(
        name=dataset_dir.resolve().name, summary=summary,
        runs_table=_runs_table(runs, {t["run_id"] for t in topologies}, fid_ids, summary["unit"]),
        topologies=topologies, fidelity_table=fid_table, fidelity_help=FIDELITY_HELP, fidelity_uri=fid_uri,
        distributions=_distributions(df, standard, view),
        card_json=card_json, card_lines=card_json.count("\n") + 1)
    out.mkdir(parents=True, exist_ok=True)
    index = out / "index.html"
    atomic_write_text(index, page)
    return index
