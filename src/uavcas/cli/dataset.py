"""`uavcas dataset synth --runs N --seed S --out DIR`: a synthetic dataset in our schema."""

from __future__ import annotations

from pathlib import Path

import typer

from uavcas.dataset.synthetic import make_flows, write_dataset

from .common import check_output, console, fail, seed_option

dataset_app = typer.Typer(help="Datasets without an emulation: synthetic flows in the dataset schema.",
                          no_args_is_help=True)


@dataset_app.command("synth")
def synth_cmd(
    out: Path = typer.Option(..., "--out", help="Dataset directory to create (must not exist, or be empty)."),
    runs: int = typer.Option(48, "--runs", min=1,
                             help="Runs; run r takes the medium preset's configuration r (16 compositions x 4 channel "
                                  "settings, cycling)."),
    seed: int = seed_option("Seed of the flows (and of each run's seed)."),
    flows_per_run: int = typer.Option(60, "--flows-per-run", min=1,
                                      help="Flows per run (about half are attack flows in attack runs)."),
) -> None:
    """Synthetic flows with a known structure (floods separable, Wormhole identical to Benign),
    built by the real flow and feature code; for trying `analyze` and `bench` without root."""
    check_output(out, "dir")
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise fail(f"--out {out}: exists and is not an empty directory")
    df = make_flows(runs, flows_per_run=flows_per_run, seed=seed)
    write_dataset(out, df)
    counts = df["label"].value_counts()
    console.print(f"wrote {len(df)} flows of {runs} runs ({len(counts)} classes) to {out}")


def register(app: typer.Typer) -> None:
    app.add_typer(dataset_app, name="dataset")
