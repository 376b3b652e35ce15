"""`uavcas analyze diversity|axes|separability DATASET --out DIR`: dataset measurements."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import typer

from uavcas.analysis.axes import axis_diversity, write_axes
from uavcas.analysis.diversity import DiversityOptions, diversity_table, write_diversity
from uavcas.analysis.iat import IAT_SOURCES, choose_source
from uavcas.analysis.separability import separability_stats, tsne_embedding, write_separability
from uavcas.dataset.read import load_any

from .common import View, check_output, console, dataset_argument, err_console, fail, one_of, path_fail, seed_option

analyze_app = typer.Typer(help="Measure a dataset: diversity, per-axis diversity, separability.", no_args_is_help=True)


VIEW_HELP = "Flow view to use when the dataset holds several."
IatSource = one_of((*IAT_SOURCES, "auto"))
IAT_HELP = ("packet (every IAT, needs per-packet sequences) | flow-mean (one mean IAT per flow) | auto "
            "(packet when every dataset has sequences, else flow-mean); one source for all datasets compared.")


def _load(path: Path, view: str | None = None):
    try:
        return load_any(path, view=view)
    except (FileNotFoundError, ValueError, KeyError, OSError) as e:
        raise path_fail(path, e) from None


@analyze_app.command("diversity")
def diversity_cmd(
    dataset: Path = dataset_argument("Dataset directory (flows.parquet) or an external sample."),
    out: Path = typer.Option(..., "--out", help="Output directory."),
    reference: list[Path] = typer.Option([], "--reference", help="Other datasets to tabulate beside it (repeatable)."),
    bins: int = typer.Option(50, "--bins", min=1, help="Log-spaced IAT bins (plus the zero bin)."),
    boot: int = typer.Option(200, "--boot", min=0, help="Bootstrap resamples (flows) for the CIs."),
    seed: int = seed_option("Seed of the bootstrap and the samples."),
    view: View | None = typer.Option(None, "--view", help=VIEW_HELP),
    pairwise: bool = typer.Option(False, "--pairwise", help="Also average over random flow pairs."),
    legacy: bool = typer.Option(True, "--legacy/--no-legacy",
                                help="Also the authors' unbounded legacy metric (packet source only)."),
    iat_source: IatSource = typer.Option("auto", "--iat-source", help=IAT_HELP),
    baseline_draws: int = typer.Option(50, "--baseline-draws", min=1,
                                       help="Benign samples drawn at each class's size for its baseline."),
) -> None:
    """Hellinger and JSD (base 2, bounded) of each class's IATs vs Benign, with CIs and a
    baseline drawn at the class's sample size."""
    check_output(out, "dir")
    paths = [dataset, *reference]
    frames = [_load(p, view) for p in paths]
    try:
        source = choose_source(frames, iat_source)
    except ValueError as e:
        raise fail(str(e)) from None
    opt = DiversityOptions(n_bins=bins, n_boot=boot, seed=seed, pairwise=pairwise, legacy=legacy,
                           iat_source=source, baseline_draws=baseline_draws)
    results = []
    for path, df in zip(paths, frames):
        name = path.name if path.name != "flows.parquet" else path.parent.name
        try:
            results.append(diversity_table(df, dataset=name, opt=opt))
        except ValueError as e:
            raise fail(f"{path}: {e}") from None
    table = pd.concat([res.table for res in results], ignore_index=True)
    write_diversity(out, table, opt, results)
    typer.echo(table[["dataset", "class", "hellinger", "jsd", "baseline_hellinger",
                      "legacy_hellinger"]].to_string(index=False))
    console.print(f"IAT source: {source} (every dataset); wrote {out / 'diversity.csv'} and diversity.json")


@analyze_app.command("axes")
def axes_cmd(
    dataset: Path = dataset_argument("Dataset directory (flows.parquet)."),
    out: Path = typer.Option(..., "--out", help="Output directory."),
    bins: int = typer.Option(50, "--bins", min=1, help="Log-spaced IAT bins (plus the zero bin)."),
    boot: int = typer.Option(200, "--boot", min=0, help="Bootstrap resamples (flows) for the CIs."),
    seed: int = seed_option("Seed of the bootstrap and the samples."),
    view: View | None = typer.Option(None, "--view", help=VIEW_HELP),
    iat_source: IatSource = typer.Option("auto", "--iat-source", help=IAT_HELP),
) -> None:
    """Internal diversity per configuration axis on benign flows (extreme values), with a
    size-matched baseline; axes confounded with others in this dataset are flagged."""
    check_output(out, "dir")
    df = _load(dataset, view)
    try:
        source = choose_source([df], iat_source)
        table, edges = axis_diversity(df, n_bins=bins, n_boot=boot, seed=seed, iat_source=source)
    except ValueError as e:
        raise fail(f"{dataset}: {e}") from None
    if table.empty:
        raise fail(f"{dataset}: no configuration axis has two values among benign flows")
    write_axes(out, table, edges, source)
    typer.echo(table[["axis", "low", "high", "hellinger", "jsd", "baseline_hellinger",
                      "baseline_jsd"]].to_string(index=False))
    for r in table.itertuples():
        if r.confounded_with:
            err_console.print(f"[yellow]confounded[/]: {r.axis} {r.low} vs {r.high} also differs in "
                              f"{r.confounded_with} (total-variation distance over runs); the difference is not the "
                              "axis's alone")


@analyze_app.command("separability")
def separability_cmd(
    dataset: Path = dataset_argument("Dataset directory (flows.parquet) or an external sample."),
    out: Path = typer.Option(..., "--out", help="Output directory."),
    tsne_samples: int = typer.Option(2000, "--tsne-samples", min=5, help="Flows in the t-SNE subsample."),
    seed: int = seed_option("Seed of the bootstrap and the samples."),
    view: View | None = typer.Option(None, "--view", help=VIEW_HELP),
) -> None:
    """Per-class mean/std of IAT, packet rate, packet size, duration; t-SNE and distribution figures."""
    check_output(out, "dir")
    df = _load(dataset, view)
    try:
        stats = separability_stats(df)
        emb = tsne_embedding(df, n_samples=tsne_samples, seed=seed)
    except ValueError as e:
        raise fail(f"{dataset}: {e}") from None
    write_separability(out, df, stats, emb)
    typer.echo(stats.to_string(index=False))
    console.print(f"wrote separability.csv, tsne.png, distributions.png to {out}")


def register(app: typer.Typer) -> None:
    app.add_typer(analyze_app, name="analyze")
