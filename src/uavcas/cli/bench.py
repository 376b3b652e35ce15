"""`uavcas bench ids DATASET --protocol ... --out DIR`: the IDS baselines under one or more
protocols, repeated over seeds; `uavcas bench leaderboard DIR ... --out DIR`: one leaderboard
from several benchmark outputs."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import typer

from uavcas.dataset.read import FORMATS, load_any
from uavcas.ids.detectors import KIND_NEEDS, KINDS, baselines, detector, detectors, names
from uavcas.ids.protocols import PROTOCOLS, SCALERS, BenchConfig, execute, prepare
from uavcas.ids.results import ResultsError, collect_results, results_frame, write_leaderboard, write_results
from uavcas.ids.torch_estimator import DL_MISSING, import_torch
from uavcas.vocabulary import TORCH_DEVICES

from .common import View, check_output, dataset_argument, err_console, fail, one_of, path_fail

BenchFormat = one_of(("auto", *FORMATS))
TorchDevice = one_of(TORCH_DEVICES)
bench_app = typer.Typer(help="Benchmarks on a dataset.", no_args_is_help=True)


def _models_help() -> str:
    """`--models` help, from the detector registry: the names by kind (the paper's baselines
    starred), what each kind needs."""
    groups = []
    for kind in KINDS:
        listed = ", ".join(s.name + "*" * s.paper_baseline for s in detectors() if s.kind == kind)
        if listed:
            groups.append(f"{kind}{f' ({KIND_NEEDS[kind]})' if KIND_NEEDS[kind] else ''}: {listed}")
    paper = f"the paper's {len(baselines())} baselines, starred"
    return f"Comma-separated detectors, or all ({paper}). {'; '.join(groups)}."


def _parse_holdout(items: list[str]) -> tuple[tuple[str, str], ...]:
    out = []
    for it in items:
        axis, sep, value = it.partition("=")
        if not sep or not axis or not value:
            raise fail(f"--holdout: expected AXIS=VALUE, got {it!r}")
        out.append((axis.strip(), value.strip()))
    return tuple(out)


def _parse_seeds(text: str) -> tuple[int, ...]:
    try:
        seeds = tuple(int(s) for s in text.split(",") if s.strip())
    except ValueError:
        raise fail(f"--seeds: expected comma-separated integers, got {text!r}") from None
    if not seeds or len(set(seeds)) != len(seeds):
        raise fail(f"--seeds: expected distinct integers, got {text!r}")
    return seeds


def _parse_list(text: str, known: tuple[str, ...], option: str) -> tuple[str, ...]:
    names = known if text.strip() == "all" else tuple(m.strip().lower() for m in text.split(",") if m.strip())
    unknown = [m for m in names if m not in known]
    if unknown or not names:
        raise fail(f"{option}: unknown {unknown} (known: {', '.join(known)}, or all)")
    return names


@bench_app.command("ids")
def ids_cmd(
    dataset: Path = dataset_argument("Dataset directory (flows.parquet), the authors' CSV (*_ts.csv) or a "
                                     "CICIDS2017/UNSW-NB15 sample."),
    out: Path = typer.Option(..., "--out", help="Output directory (one sub-directory per protocol when several)."),
    protocol: str = typer.Option("multiclass", "--protocol",
                                 help="binary | multiclass | ood | cross-condition, comma-separated, or all."),
    models: str = typer.Option("all", "--models", help=_models_help()),
    scaler: str = typer.Option("standard", "--scaler", help="standard | minmax | robust."),
    epochs: int = typer.Option(50, "--epochs", min=1,
                               help="Max epochs of the neural models (early stopping on the grouped validation "
                                    "split)."),
    holdout: list[str] = typer.Option([], "--holdout", help="AXIS=VALUE held out (cross-condition; repeatable)."),
    seeds: str = typer.Option("0,1,2,3,4", "--seeds",
                              help="Comma-separated seeds: one grouped split and model seed each; mean ± std over "
                                   "them."),
    features: str = typer.Option(None, "--features",
                                 help="A feature set of the schema (e.g. cic, paper) or comma-separated columns "
                                      "(default: the dataset's)."),
    importance: bool = typer.Option(True, "--importance/--no-importance",
                                    help="Permutation importance of the tree models "
                                         f"({', '.join(s.display for s in detectors() if s.tree)})."),
    train_cap: int = typer.Option(0, "--train-cap", min=0,
                                  help="At most N training (and validation) flows per run and class, seeded (0: all); "
                                       "test flows are never capped."),
    min_class_runs: int = typer.Option(0, "--min-class-runs", min=0,
                                       help="Leave out the flows of classes held by fewer than N runs, listed in the "
                                            "notes (0: refuse such a class, naming it)."),
    threads: int = typer.Option(0, "--threads", min=0, help="Threads per model (0: cores available)."),
    device: TorchDevice = typer.Option("auto", "--device", help="Where the torch models train: auto (CUDA when torch "
                                                                "sees a GPU, else the CPU), cpu or cuda. Recorded per "
                                                                "fit."),
    fmt: BenchFormat = typer.Option("auto", "--format", help="What DATASET is (auto: by its files)."),
    view: View | None = typer.Option(None, "--view", help="Flow view when the dataset holds several."),
) -> None:
    """Train and evaluate the baselines; writes results/summary/splits/confusion CSVs, figures,
    results.md per protocol and leaderboard.csv/md."""
    check_output(out, "dir")
    protocols = _parse_list(protocol, PROTOCOLS, "--protocol")
    if scaler not in SCALERS:
        raise fail(f"--scaler: unknown {scaler!r} (known: {', '.join(SCALERS)})")
    if models.strip() == "all":
        chosen = tuple(s.name for s in baselines())
    else:
        chosen = _parse_list(models, names(), "--models")
    if any(detector(m).needs_torch for m in chosen):
        try:
            import_torch()  # the optional `dl` extra, checked when a deep detector is chosen
        except ImportError:
            raise fail(DL_MISSING) from None
    feats = None
    if features:
        feats = features.strip() if "," not in features else tuple(f.strip() for f in features.split(",") if f.strip())
    cfg = BenchConfig(models=chosen, scaler=scaler, epochs=epochs, seeds=_parse_seeds(seeds),
                      holdout=_parse_holdout(holdout), features=feats, importance=importance,
                      train_cap=train_cap or None, min_class_runs=min_class_runs, n_threads=threads or None,
                      device=device)
    try:
        df = load_any(dataset, None if fmt == "auto" else fmt, view=view)
        prepared = [prepare(df, p, cfg) for p in protocols]  # refuse bad input before any fit
    except (FileNotFoundError, ValueError, KeyError, OSError) as e:
        raise path_fail(dataset, e) from None
    frames, notes = [], []
    for prep in prepared:
        cfg.progress = lambda msg, p=prep.protocol: err_console.print(f"[dim]{p}[/] {msg}", highlight=False)
        res = execute(prep, cfg)
        meta = {"dataset": str(dataset), "scaler": scaler, "epochs": epochs, "seeds": list(cfg.seeds), "device": device,
                "train_cap": cfg.train_cap, "min_class_runs": cfg.min_class_runs,
                "models": list(chosen), "holdout": [f"{a}={v}" for a, v in cfg.holdout],
                "absent_features": df.attrs.get("absent_features", [])}
        where = out if len(prepared) == 1 else out / prep.protocol
        write_results(res, where, meta)
        frames.append(results_frame(res))
        notes += [f"{prep.protocol}: {n}" for n in res.notes]
    write_leaderboard(out, pd.concat(frames, ignore_index=True), notes)
    typer.echo((out / "leaderboard.md").read_text())


@bench_app.command("leaderboard")
def leaderboard_cmd(
    results: list[Path] = typer.Argument(..., help="Benchmark output directories (their results.csv, searched "
                                                   "recursively)."),
    out: Path = typer.Option(..., "--out", help="Output directory for leaderboard.csv and leaderboard.md."),
) -> None:
    """One leaderboard (mean ± std over seeds) from several `bench ids` outputs."""
    check_output(out, "dir")
    try:
        allr, files = collect_results(results)
    except ResultsError as e:
        raise fail(str(e)) from None
    write_leaderboard(out, allr, [f"from {f}" for f in files])
    typer.echo((out / "leaderboard.md").read_text())


def register(app: typer.Typer) -> None:
    app.add_typer(bench_app, name="bench")
