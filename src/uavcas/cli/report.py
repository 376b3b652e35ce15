"""`uavcas report DATASET_DIR --out DIR`: one self-contained HTML page about a dataset (`uavcas.report`)."""

from __future__ import annotations

from pathlib import Path

import typer

from uavcas.dataset.store import DatasetError
from uavcas.report.dataset_report import ReportError, write_report

from .common import check_output, console, dataset_argument, fail


def report_cmd(
    dataset: Path = dataset_argument(),
    out: Path = typer.Option(..., "--out",
                             help="Directory for index.html, the one self-contained file written (figures inlined)."),
) -> None:
    """Write a self-contained HTML report of a dataset: summary, runs, topology, fidelity, distributions, card."""
    check_output(out, "dir")
    try:
        index = write_report(dataset, out)
    except (DatasetError, ReportError) as e:
        raise fail(str(e)) from None
    console.print(f"report written to {index}")


def register(app: typer.Typer) -> None:
    app.command("report")(report_cmd)
