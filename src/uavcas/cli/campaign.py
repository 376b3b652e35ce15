"""`uavcas campaign ...`: manifests (and, with the campaign executor, runs)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from uavcas.campaign import CampaignError, Extraction, read_manifest, run_campaign, write_manifest
from uavcas.dataset.runs import dataset_runs, flagged_lines
from uavcas.report.dataset_report import write_report
from uavcas.scenario import PRESETS, manifest, parse_shard, select_shard
from uavcas.schema import CLASSES
from uavcas.twin.profile import load_profile
from uavcas.vocabulary import FIDELITY_POLICIES

from .common import (
    ExtractView,
    Standard,
    Termination,
    check_output,
    console,
    fail,
    features_option,
    min_attack_fraction_option,
    one_of,
    profile_option,
    seed_option,
    termination_option,
    view_option,
)

Preset = one_of(PRESETS)

campaign_app = typer.Typer(help="Campaigns of scenarios: manifests, runs.", no_args_is_help=True)


@campaign_app.command("manifest")
def manifest_cmd(
    out: Path = typer.Option(..., "--out", help="JSONL file to write (one scenario per line)."),
    preset: Preset = typer.Option("paper", "--preset", help="The campaign's scenarios."),
    seed: int = seed_option("Seed of the permutation and of the run seeds."),
    shard: str = typer.Option(None, "--shard", help="K/N: keep the K-th of N slices."),
) -> None:
    """Write the campaign's scenarios in seeded-permutation order."""
    check_output(out, "file")
    try:
        sh = parse_shard(shard) if shard is not None else None
    except ValueError as e:
        raise fail(f"--{e}") from None

    entries = manifest(preset, seed=seed, shard=sh)
    write_manifest(out, entries)
    console.print(f"wrote {len(entries)} scenarios of preset [bold]{preset}[/] to {out}")


@campaign_app.command("run")
def run_cmd(
    out: Path = typer.Option(..., "--out", help="Dataset directory (created; re-running resumes it)."),
    preset: Preset | None = typer.Option(None, "--preset", help="The campaign's scenarios (default quick)."),
    manifest_file: Path = typer.Option(None, "--manifest", help="A manifest JSONL instead of a preset."),
    seed: int = seed_option("Campaign seed (with --preset)."),
    shard: str = typer.Option(None, "--shard", help="K/N: run only the K-th of N slices."),
    jobs: int = typer.Option(1, "--jobs", min=1, help="Scenarios emulated at once on this host."),
    scheduler: str = typer.Option(None, "--scheduler", help="Dask scheduler, e.g. tcp://HOST:8786."),
    profile: str = profile_option(),
    retries: int = typer.Option(2, "--retries", min=0, help="Extra tries for a failed run."),
    fidelity: one_of(FIDELITY_POLICIES) = typer.Option("flag", "--fidelity",
                                 help="A run whose fidelity audit fails: 'flag' (keep it, counted in dataset.json) "
                                      "or 'retry' (try again up to --retries, then keep the last, flagged)."),
    report: bool = typer.Option(True, "--report/--no-report", help="Write DATASET_DIR/report/index.html at the end."),
    min_attack_fraction: float = min_attack_fraction_option(),
    view: ExtractView = view_option(),
    features: Standard = features_option(),
    termination: Termination | None = termination_option(),
    mavlink_signing: bool = typer.Option(False, "--mavlink-signing/--no-mavlink-signing",
                                         help="Every run signs its MAVLink (MAVLink 2 signing, a per-run key): "
                                              "the defended twin."),
) -> None:
    """Plan, emulate, extract and label every scenario; append each run's shard to the dataset."""
    check_output(out, "dir")

    try:  # before anything is planned or created
        extraction = Extraction(view=view, termination=termination, min_attack_fraction=min_attack_fraction,
                                features=features)
    except ValueError as e:
        raise fail(str(e)) from None
    if preset is not None and manifest_file is not None:
        raise fail("give --preset or --manifest, not both")
    try:
        sh = parse_shard(shard) if shard is not None else None
        if manifest_file is not None:
            entries = read_manifest(manifest_file)
            if sh is not None:
                entries = select_shard(entries, sh)
        else:
            preset = preset or "quick"
            entries = manifest(preset, seed=seed, shard=sh)
        if profile is not None:
            load_profile(profile)
        result = run_campaign(entries, out, jobs=jobs, scheduler=scheduler, profile=profile, retries=retries,
                              extraction=extraction, fidelity=fidelity, mavlink_signing=mavlink_signing)
    except (CampaignError, ValueError) as e:
        raise fail(str(e).splitlines()[0]) from None
    except KeyboardInterrupt:
        raise fail("interrupted; the dataset holds the finished runs, re-run the command to resume", 130) from None
    card = result.card
    table = Table(title=f"dataset {out}")
    table.add_column("class")
    table.add_column("flows", justify="right")
    for c in CLASSES:
        n = card.get("class_counts", {}).get(c, 0)
        if n:
            table.add_row(c, str(n))
    console.print(table)
    console.print(
        f"runs: {len(result.done)} done now, {len(result.skipped)} already done, {len(result.failed)} failed; "
        f"flows: {card.get('n_flows', 0)}; wall time {result.wall_s:.0f} s"
    )

    flagged = flagged_lines(dataset_runs(out, card)) if card else []
    if flagged:  # kept in the dataset (counted in dataset.json), so say which and why
        console.print(f"[yellow]{len(flagged)} run(s) kept flagged, their fidelity audit did not pass:[/]")
        for line in flagged:
            console.print(f"  {line}", highlight=False, soft_wrap=True, markup=False)
    console.print(f"dataset: {Path(out).resolve()}/flows.parquet")
    if report and card:
        console.print(f"report: {write_report(out, Path(out) / 'report').resolve()}")
    if result.failed:
        raise fail(f"{len(result.failed)} run(s) failed: "
                   + "; ".join(f"{o.index}: {o.error}" for o in result.failed[:3]), 1)


def register(app: typer.Typer) -> None:
    app.add_typer(campaign_app, name="campaign")
