"""`uavcas bench ids DATASET --protocol ... --out DIR`: the IDS baselines under one protocol."""

from __future__ import annotations

from pathlib import Path

import typer

from .common import err_console, fail

bench_app = typer.Typer(help="Benchmarks on a dataset.", no_args_is_help=True)


def _parse_holdout(items: list[str]) -> tuple[tuple[str, str], ...]:
    out = []
    for it in items:
        axis, sep, value = it.partition("=")
        if not sep or not axis or not value:
            raise fail(f"--holdout: expected AXIS=VALUE, got {it!r}")
        out.append((axis.strip(), value.strip()))
    return tuple(out)


@bench_app.command("ids")
def ids_cmd(
    dataset: Path = typer.Argument(..., help="Dataset directory (flows.parquet), the authors' CSV (*_ts.csv) or a CICIDS2017/UNSW-NB15 sample."),
    out: Path = typer.Option(..., "--out", help="Output directory."),
    protocol: str = typer.Option("multiclass", "--protocol", help="binary | multiclass | ood | cross-condition."),
    models: str = typer.Option("all", "--models", help="Comma-separated: lr,sgd,rf,mlp,lightgbm,cnn1d,lstm,convnet,tinyml,cnn_bilstm (or all)."),
    scaler: str = typer.Option("standard", "--scaler", help="standard | minmax | robust."),
    epochs: int = typer.Option(50, "--epochs", min=1, help="Max epochs of the neural models (early stopping on validation)."),
    holdout: list[str] = typer.Option([], "--holdout", help="AXIS=VALUE held out (cross-condition; repeatable)."),
    seed: int = typer.Option(0, "--seed"),
    threads: int = typer.Option(0, "--threads", min=0, help="Threads per model (0: cores available)."),
    fmt: str = typer.Option("auto", "--format", help="auto | uavcas | uavcas-csv | cicids2017 | unsw-nb15."),
    view: str = typer.Option(None, "--view", help="Flow view when the dataset holds several (5tuple | hostpair)."),
) -> None:
    """Train and evaluate the baselines; writes results.csv/json/md (+ confusion matrices)."""
    from uavcas.dataset.read import load_any
    from uavcas.ids.models import MODELS
    from uavcas.ids.protocols import PROTOCOLS, SCALERS, BenchConfig, run_protocol
    from uavcas.ids.results import write_results
    from uavcas.ids.torch_estimator import DL_MISSING

    if protocol not in PROTOCOLS:
        raise fail(f"--protocol: unknown {protocol!r} (known: {', '.join(PROTOCOLS)})")
    if scaler not in SCALERS:
        raise fail(f"--scaler: unknown {scaler!r} (known: {', '.join(SCALERS)})")
    names = MODELS if models.strip() == "all" else tuple(m.strip().lower() for m in models.split(",") if m.strip())
    unknown = [m for m in names if m not in MODELS]
    if unknown or not names:
        raise fail(f"--models: unknown {unknown} (known: {', '.join(MODELS)})")
    if any(m in MODELS[5:] for m in names):
        try:
            import torch  # noqa: F401
        except ImportError:
            raise fail(DL_MISSING) from None
    cfg = BenchConfig(models=names, scaler=scaler, epochs=epochs, seed=seed,
                      holdout=_parse_holdout(holdout), n_threads=threads or None,
                      progress=lambda msg: err_console.print(f"[dim]{protocol}[/] {msg}", highlight=False))
    try:
        df = load_any(dataset, None if fmt == "auto" else fmt, view=view)
        res = run_protocol(df, protocol, cfg)
    except (FileNotFoundError, ValueError, KeyError, OSError) as e:
        raise fail(f"{dataset}: {e}") from None
    meta = {"dataset": str(dataset), "scaler": scaler, "epochs": epochs, "seed": seed,
            "models": list(names), "holdout": [f"{a}={v}" for a, v in cfg.holdout],
            "absent_features": df.attrs.get("absent_features", [])}
    write_results(res, out, meta)
    typer.echo((out / "results.md").read_text())


def register(app: typer.Typer) -> None:
    app.add_typer(bench_app, name="bench")
