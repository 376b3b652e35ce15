"""Where runs execute: a local pool of N concurrent runs, or a dask.distributed cluster.

Both yield `RunOutcome`s as runs finish and retry failures by one rule (`retry.Retries`). The
local pool uses threads because each run is a child process (`campaign.worker`) plus an
extraction; the threads only wait. On Dask, each run asks for the
worker resource `emulator=1`, so a worker started with `--resources emulator=1` emulates one
scenario at a time, and the outcome (shard bytes and the small run files) returns to the client.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait

from uavcas.scenario import ManifestEntry

from .layout import CampaignDir
from .retry import Retries
from .task import Extraction, RunOutcome, execute_entry


def run_local(
    entries: list[ManifestEntry],
    cdir: CampaignDir,
    jobs: int,
    profile: str | None,
    retries: int,
    on_retry: Callable[[RunOutcome, int], None] | None = None,
    extraction: Extraction = Extraction(),
    fidelity: str = "flag",
    mavlink_signing: bool = False,
) -> Iterator[RunOutcome]:
    """Run entries `jobs` at a time into their run directories; retry a failure `retries` times
    (and a run whose fidelity failed, with `fidelity="retry"`: see `task.execute_entry`)."""
    tries = Retries(retries, on_retry)
    by_index = {e.index: e for e in entries}
    pending = list(entries)

    def submit(pool: ThreadPoolExecutor, e: ManifestEntry) -> Future:
        tries.started(e.index)
        cdir.reset(e.index)
        return pool.submit(execute_entry, e, str(cdir.run_dir(e.index)), profile, extraction=extraction,
                           fidelity=fidelity, mavlink_signing=mavlink_signing)

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        running: set[Future] = set()
        while pending or running:
            while pending and len(running) < jobs:
                running.add(submit(pool, pending.pop(0)))
            done, running = wait(running, return_when=FIRST_COMPLETED)
            for fut in done:
                out: RunOutcome = fut.result()
                if tries.again(out):
                    pending.insert(0, by_index[out.index])
                    continue
                yield out


def run_dask(
    entries: list[ManifestEntry],
    address: str,
    profile: str | None,
    retries: int,
    on_retry: Callable[[RunOutcome, int], None] | None = None,
    connect_timeout_s: float = 30.0,
    extraction: Extraction = Extraction(),
    fidelity: str = "flag",
    mavlink_signing: bool = False,
) -> Iterator[RunOutcome]:
    """Submit every entry to the scheduler at `address` (tcp://HOST:8786); yield as they finish."""
    # on use: dask's distributed is heavy and only a campaign on a scheduler needs it
    from distributed import Client, as_completed

    with Client(address, timeout=connect_timeout_s) as client:
        tries = Retries(retries, on_retry)
        by_index = {e.index: e for e in entries}

        def submit(e: ManifestEntry):
            n = tries.started(e.index)
            return client.submit(
                execute_entry,
                e.to_dict(),
                None,
                profile,
                return_files=True,
                extraction=extraction,
                fidelity=fidelity,
                mavlink_signing=mavlink_signing,
                resources={"emulator": 1},
                pure=False,
                key=f"uavcas-run-{e.index}-try{n}",
            )

        futures = as_completed([submit(e) for e in entries])
        for fut in futures:
            try:
                out: RunOutcome = fut.result()
            except Exception as exc:  # the worker died or the task could not run at all
                idx = int(str(fut.key).split("-")[2])
                out = RunOutcome(index=idx, ok=False, host="?", wall_s=0.0, error=f"dask: {exc}")
            if tries.again(out):
                futures.add(submit(by_index[out.index]))
                continue
            yield out
