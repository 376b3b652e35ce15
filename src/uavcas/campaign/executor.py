"""Where runs execute on this host: a local pool of N concurrent runs (a dask.distributed
cluster: `campaign.cluster`).

Both yield `RunOutcome`s as runs finish and retry failures by one rule (`retry.Retries`). The
local pool uses threads because each run is a child process (`campaign.worker`) plus an
extraction; the threads only wait.
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

