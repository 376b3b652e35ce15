"""`uavcas info DATASET`: what a dataset holds (its card, `uavcas.dataset.store`, and its runs,
`uavcas.dataset.runs`), or its columns (`uavcas.dataset.dictionary`)."""

from __future__ import annotations

import sys
from pathlib import Path

import pyarrow.parquet as pq
import typer
from rich.table import Table

from uavcas.dataset.dictionary import DictionaryError, columns
from uavcas.dataset.runs import dataset_runs, percent
from uavcas.dataset.store import card_standard, read_card
from uavcas.views import card_view

from .common import console, dataset_argument, dataset_errors, fail


def info_cmd(
    dataset_dir: Path = dataset_argument(),
    columns: bool = typer.Option(False, "--columns", help="List every column of flows.parquet with its dtype, unit "
                                                         "and meaning (tab-separated) instead."),
) -> None:
    """Class counts, feature standard, views, fidelity and the runs of a dataset (or its columns)."""
    try:
        card = read_card(dataset_dir)
    except dataset_errors() as exc:
        raise fail(str(exc)) from None
    if columns:
        _print_columns(dataset_dir, card)
        return
    total = int(card.get("n_flows", 0))
    unit = card_view(card).row.plural
    # the heading and the summary are lines of their own: a table's title and caption wrap at the
    # table's width, which cut a long dataset path in two even in a pipe
    console.print(f"{dataset_dir}: {total} {unit}, {card.get('n_runs', 0)} runs", highlight=False, soft_wrap=True)
    table = Table()
    table.add_column("class")
    table.add_column("flows", justify="right")
    table.add_column("share", justify="right")
    for cls, n in card.get("class_counts", {}).items():
        table.add_row(cls, str(n), percent(n, total))
    std = card_standard(card)
    console.print(table)
    console.print(f"features: {std}; views: {', '.join(card.get('views', []))}; "
                  f"labels: {', '.join(card.get('label_modes', []))}; schema v{card.get('schema_version')}",
                  highlight=False, soft_wrap=True)
    runs = dataset_runs(dataset_dir, card)
    fid = card.get("fidelity") or {}
    console.print("fidelity: " + (", ".join(f"{n} {v}" for v, n in fid.items()) or "not recorded")
                  + f"; {sum(r.flagged for r in runs)} run(s) kept flagged", highlight=False, soft_wrap=True)
    per_run = Table(title="runs")
    for name, justify in (("run", "right"), ("config", "left"), (unit, "right"), ("classes", "left"),
                          ("fidelity", "left")):
        per_run.add_column(name, justify=justify, overflow="fold")
    for r in runs:
        per_run.add_row(r.run_id, r.config, str(r.rows),
                        ", ".join(f"{c} {n}" for c, n in r.classes.items()),
                        r.verdict + (f": {'; '.join(r.failed)}" if r.failed else ""))
    console.print(per_run)


def _print_columns(dataset_dir: Path, card: dict) -> None:
    """Every column of flows.parquet, from the data dictionary: name, dtype, unit, meaning (TSV)."""
    path = Path(dataset_dir) / "flows.parquet"
    if not path.is_file():
        raise fail(f"{dataset_dir}: no flows.parquet beside dataset.json")
    try:
        cols = columns(pq.read_schema(path), card_standard(card), card_view(card))
    except DictionaryError as exc:
        raise fail(str(exc)) from None
    sys.stdout.write("column\tdtype\tunit\tmeaning\n")
    sys.stdout.write("".join(f"{c.name}\t{c.dtype}\t{c.unit}\t{c.meaning}\n" for c in cols))


def register(app: typer.Typer) -> None:
    app.command("info")(info_cmd)
