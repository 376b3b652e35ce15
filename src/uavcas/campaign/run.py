"""`run_campaign`: every scenario of a manifest -> one dataset, resumable, local or on Dask."""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from uavcas.atomic import atomic_write_bytes, atomic_write_text
from uavcas.dataset.store import rebuild
from uavcas.scenario import ManifestEntry
from uavcas.vocabulary import FIDELITY_POLICIES

from .executor import run_local
from .layout import CampaignDir, CampaignError
from .task import Extraction, RunOutcome

DEFAULT_RETRIES = 2


@dataclass
class CampaignResult:
    out_dir: Path
    done: list[int] = field(default_factory=list)  # finished in this invocation
    skipped: list[int] = field(default_factory=list)  # already DONE before
    failed: list[RunOutcome] = field(default_factory=list)
    card: dict = field(default_factory=dict)
    wall_s: float = 0.0


def _commit(cdir: CampaignDir, out: RunOutcome) -> None:
    """Make a finished run durable: its files (Dask), its shard, then the DONE marker."""
    run_dir = cdir.run_dir(out.index)
    run_dir.mkdir(parents=True, exist_ok=True)
    for name, data in out.files.items():
        atomic_write_bytes(run_dir / name, data)
    atomic_write_bytes(cdir.shard_path(out.index), out.shard)
    atomic_write_text(run_dir / "outcome.json", json.dumps(out.summary(), indent=1, sort_keys=True) + "\n")
    cdir.mark_done(out.index, {"index": out.index, "n_flows": out.n_flows, "host": out.host})


def preflight_local() -> None:
    if os.geteuid() != 0:
        raise CampaignError(
            "campaign runs emulate on network namespaces and need root "
            "(or pass --scheduler to run on a Dask cluster of root workers)"
        )


def run_campaign(
    entries: list[ManifestEntry],
    out_dir: str | Path,
    jobs: int = 1,
    scheduler: str | None = None,
    profile: str | None = None,
    retries: int = DEFAULT_RETRIES,
    console: Console | None = None,
    extraction: Extraction = Extraction(),
    fidelity: str = "flag",
    mavlink_signing: bool = False,
) -> CampaignResult:
    console = console or Console(stderr=True)
    if jobs < 1:
        raise CampaignError(f"--jobs must be >= 1, got {jobs}")
    if fidelity not in FIDELITY_POLICIES:
        raise CampaignError(f"--fidelity must be one of {', '.join(FIDELITY_POLICIES)}, got {fidelity!r}")
    if scheduler is None:
        preflight_local()
    cdir = CampaignDir(Path(out_dir))
    cdir.root.mkdir(parents=True, exist_ok=True)
    cdir.bind_manifest(entries)
    cdir.bind_extraction(extraction)  # a resumed campaign keeps its view and termination: rows never mix
    cdir.bind_emulation(mavlink_signing=mavlink_signing)  # and its runs' MAVLink signing
    cdir.prune_orphan_shards()
    result = CampaignResult(out_dir=cdir.root)
    todo = []
    for e in entries:
        if cdir.is_done(e.index):
            result.skipped.append(e.index)
        else:
            todo.append(e)
    t0 = time.monotonic()

    def on_retry(out: RunOutcome, attempt: int) -> None:
        why = "fidelity failed" if out.ok else f"failed: {out.error}"
        console.print(f"[yellow]run {out.index} {why} (try {attempt}/{retries + 1}); retrying[/]")

    columns = (
        TextColumn("[bold]campaign[/]"), BarColumn(), MofNCompleteColumn(),
        TextColumn("{task.fields[status]}"), TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
    )
    try:
        with Progress(*columns, console=console, transient=False) as progress:
            task = progress.add_task("runs", total=len(entries), completed=len(result.skipped), status="")

            queue = ""  # on Dask: how many runs are queued and running, refreshed while they wait

            def status() -> str:
                return f"{queue}done {len(result.done) + len(result.skipped)} failed {len(result.failed)}"

            def on_queue(text: str) -> None:
                nonlocal queue
                queue = f"{text} "
                progress.update(task, status=status())

            progress.update(task, status=status())
            if scheduler:
                # on use: dask's distributed is heavy and only a campaign on a scheduler needs it
                from .cluster import run_dask

                outcomes = run_dask(todo, scheduler, profile, retries, on_retry, extraction=extraction,
                                    fidelity=fidelity, mavlink_signing=mavlink_signing, on_status=on_queue,
                                    on_note=lambda line: console.print(line, highlight=False))
            else:
                outcomes = run_local(todo, cdir, jobs, profile, retries, on_retry, extraction=extraction,
                                     fidelity=fidelity, mavlink_signing=mavlink_signing)
            for out in outcomes:
                if out.ok:
                    _commit(cdir, out)
                    result.done.append(out.index)
                    if out.fidelity == "fail":
                        console.print(f"[yellow]run {out.index} kept, flagged: fidelity failed[/]")
                else:
                    result.failed.append(out)
                    console.print(f"[red]run {out.index} failed after {retries + 1} tries: {out.error}[/]")
                progress.update(task, advance=1, status=status())
    finally:
        # Whatever happened (Ctrl-C included), the dataset reflects exactly the DONE runs.
        cdir.prune_orphan_shards()
        if any((cdir.root / "shards").glob("*.parquet")):
            result.card = rebuild(cdir.root)
        result.wall_s = round(time.monotonic() - t0, 1)
    return result
