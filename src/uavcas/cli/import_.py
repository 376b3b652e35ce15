"""`uavcas import SRC --out DATASET`: the authors' CSV layout read into a dataset directory
(`uavcas.dataset.store.import_layout`). The module's name has a trailing underscore: `import` is a
Python keyword."""

from __future__ import annotations

from pathlib import Path

import typer

from uavcas.dataset.read import IMPORT_FORMATS
from uavcas.dataset.store import import_layout

from .common import check_output, console, dataset_errors, err_console, fail, one_of


def import_cmd(
    src: Path = typer.Argument(...,
                               help="Directory with UAV-CAS_stat.csv / UAV-CAS_ts.csv (or _cfg variants), or one of "
                                    "them."),
    fmt: one_of(IMPORT_FORMATS) = typer.Option("uavcas-csv", "--format",
                                               help="uavcas-csv: the authors' released layout."),
    out: Path = typer.Option(..., "--out", help="New dataset directory to create."),
) -> None:
    """Import the authors' CSV layout (theirs as released, or ours) into a dataset directory."""
    check_output(out, "dir")
    try:
        card, imp = import_layout(src, out)
    except dataset_errors() as exc:
        raise fail(str(exc)) from None
    for note in imp.notes:
        console.print(note, highlight=False)
    err_console.print(f"the layout lacks: {', '.join(imp.lacks)}", highlight=False, soft_wrap=True)
    console.print(f"imported {card['n_flows']} flows ({card['features']['standard']} features) -> {out}",
                  highlight=False)


def register(app: typer.Typer) -> None:
    app.command("import")(import_cmd)
