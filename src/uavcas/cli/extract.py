"""`uavcas extract RUN_DIR --out DATASET`: one run's labelled flows added to a dataset
(`uavcas.dataset.store.extract_run`)."""

from __future__ import annotations

from pathlib import Path

import typer

from uavcas.dataset.store import extract_run
from uavcas.views import view as view_spec
from uavcas.vocabulary import LABEL_MODES

from .common import (
    ExtractView,
    Standard,
    Termination,
    allow_truncated_option,
    check_output,
    console,
    dataset_errors,
    fail,
    features_option,
    min_attack_fraction_option,
    one_of,
    run_dir_argument,
    termination_option,
    view_option,
    warn,
)


def extract_cmd(
    run_dir: Path = run_dir_argument(),
    out: Path = typer.Option(..., "--out", help="Dataset directory to add the run's shard to."),
    view: ExtractView = view_option(),
    features: Standard = features_option(),
    labels: one_of(LABEL_MODES) = typer.Option("ours", "--labels",
                                               help="ours (from each packet's effect) or paper (IP membership)."),
    min_packets: int = typer.Option(None, "--min-packets", help="Drop smaller flows (default by view)."),
    termination: Termination | None = termination_option(),
    allow_truncated: bool = allow_truncated_option(),
    min_attack_fraction: float = min_attack_fraction_option(),
    allow_incomplete: bool = typer.Option(False, "--allow-incomplete",
                                          help="Also extract a run that was killed or failed (marked incomplete)."),
) -> None:
    """Extract one run into the dataset directory --out (its shard is replaced if it was extracted before)."""
    check_output(out, "dir")

    try:
        info = extract_run(run_dir, out, view=view, labels=labels, min_packets=min_packets, termination=termination,
                           allow_truncated=allow_truncated, features=features,
                           min_attack_fraction=min_attack_fraction, allow_incomplete=allow_incomplete)  # fmt: skip
    except dataset_errors() as exc:
        raise fail(str(exc)) from None
    warn(f"truncated capture {t}; kept the packets before it" for t in info.truncations)
    if not info.complete:
        warn([f"run {info.run_id} is incomplete (exit status {info.run_exit_status}); its shard is marked so"])
    counts = ", ".join(f"{k} {v}" for k, v in sorted(info.class_counts.items()))
    rows = view_spec(info.view).row.plural
    console.print(f"run [bold]{info.run_id}[/]: {info.n_flows} {rows} from {info.n_packets} packets ({counts}) "
                  f"-> {out}", highlight=False)
    if info.impure_dropped:
        console.print(f"{info.impure_dropped} flow(s) left out: attack_fraction below {min_attack_fraction:g}")


def register(app: typer.Typer) -> None:
    app.command("extract")(extract_cmd)
