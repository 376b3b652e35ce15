"""`uavcas publish DATASET --out DIR`: the dataset as a self-contained publication
(`uavcas.dataset.publish`): its Parquet shards, the card, Croissant metadata and a README card."""

from __future__ import annotations

from pathlib import Path

import typer

from uavcas.dataset.croissant import CroissantError
from uavcas.dataset.publish import publish
from uavcas.dataset.store import DatasetError

from .common import check_output, console, dataset_argument, err_console, fail


def publish_cmd(
    dataset: Path = dataset_argument(),
    out: Path = typer.Option(..., "--out", help="Directory to create (absent, or empty): shards/, dataset.json, "
                                                 "croissant.json, README.md."),
    name: str = typer.Option(None, "--name", help="The dataset's name in croissant.json and README.md "
                                                  "(default: the dataset directory's name)."),
    license: str = typer.Option("CC-BY-4.0", "--license", help="Licence of the generated data: an SPDX identifier "
                                                               "or a URL (the calibration data keep their own)."),
    version: str = typer.Option("1.0.0", "--dataset-version", help="Version of this publication (MAJOR.MINOR.PATCH)."),
    url: str = typer.Option(None, "--url", help="The publication's web page, if it has one."),
) -> None:
    """Publish a dataset: its Parquet shards (hard-linked on the same file system, else copied), its
    card, a Croissant file validated by mlcroissant, and a README dataset card (classes, labelling
    rules, fidelity, every column with its unit, the calibration data's licence)."""
    check_output(out, "dir")

    try:
        p = publish(dataset, out, name=name, license=license, version=version, url=url)
    except (DatasetError, CroissantError, FileExistsError) as e:
        raise fail(str(e)) from None  # the library's messages name their path
    for w in p.warnings:
        err_console.print(f"[yellow]mlcroissant warning:[/] {w}", highlight=False, soft_wrap=True)
    console.print(f"published {p.rows} rows in {p.shards} shard(s) ({p.linked} hard-linked) to {out}: "
                  f"croissant.json valid (mlcroissant {p.croissant_version}, {len(p.warnings)} warning(s)), README.md",
                  highlight=False, soft_wrap=True)


def register(app: typer.Typer) -> None:
    app.command("publish")(publish_cmd)
