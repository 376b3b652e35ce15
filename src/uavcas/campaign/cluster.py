"""A campaign's runs on a dask.distributed cluster (`uavcas campaign run --scheduler tcp://HOST:PORT`).

Each run is one Dask task asking for the worker resource `emulator=1`; a worker started with
`--nthreads 1 --resources emulator=1` (as root, one per emulation host) takes one at a time and
returns the outcome (shard bytes and the small run files) to the client, which alone writes the
dataset. Before anything is submitted the cluster must offer that resource: a scheduler that
cannot be reached, or whose workers all lack it for `EMULATOR_WAIT_S`, is refused in one line
(Dask itself would queue the runs forever).

What "once" means: a try whose worker dies is retried, by Dask on another worker (its
`allowed_failures`), or, once Dask gives up, by the campaign's `Retries` under a new key; a
failed outcome likewise. Exactly one outcome per run reaches the dataset: a run has one task in
flight at a time (the next try is submitted only after the previous one ended), a dead try
returns nothing (its output lived in a temporary directory of its worker), and the keys carry a
token of this campaign, so two campaigns on one scheduler never share a result.
"""

from __future__ import annotations

import os
import socket
import time
import uuid
from collections import deque
from collections.abc import Callable, Iterator

from distributed import Client, Future, get_worker

from uavcas.scenario import ManifestEntry

from .layout import CampaignError
from .retry import Retries
from .task import Extraction, RunOutcome, execute_entry

RESOURCE = "emulator"
WORKER_FLAGS = "--nthreads 1 --resources emulator=1"
# how long the scheduler may be out of reach, or lack any emulator worker: with the CLI's start-up,
# a refusal within 30 s
EMULATOR_WAIT_S = 20.0
CONNECT_S = 20.0
POLL_S = 0.5  # how often the queue is looked at (progress, finished runs, workers)


def _first_line(e: BaseException) -> str:
    text = str(e).strip().splitlines()
    return f"{type(e).__name__}: {text[0]}" if text else type(e).__name__


def connect(address: str, timeout_s: float) -> Client:
    """A client of the scheduler at `address`; an unreachable one is a one-line CampaignError."""
    try:
        return Client(address, timeout=timeout_s, set_as_default=False)
    except (OSError, TimeoutError) as e:
        raise CampaignError(f"cannot reach the Dask scheduler at {address} within {timeout_s:.0f} s "
                            f"({_first_line(e)})") from None


def _workers(client: Client) -> dict[str, dict]:
    return client.scheduler_info(n_workers=-1)["workers"]


def _emulators(workers: dict[str, dict]) -> list[str]:
    return [a for a, w in workers.items() if (w.get("resources") or {}).get(RESOURCE, 0) >= 1]


def refusal(address: str, n_workers: int, waited_s: float) -> str:
    """The one line naming the flag a worker needs."""
    which = f"{n_workers} worker(s) without it" if n_workers else "no worker connected"
    return (f"no worker of the Dask scheduler at {address} offers the {RESOURCE} resource after {waited_s:.0f} s "
            f"({which}): start one worker per emulation host, as root, with "
            f"`dask worker {address} {WORKER_FLAGS}`")


def await_emulators(client: Client, address: str, timeout_s: float = EMULATOR_WAIT_S) -> list[str]:
    """The addresses of workers offering RESOURCE, waiting up to `timeout_s` for one to join."""
    deadline = time.monotonic() + timeout_s
    while True:
        workers = _workers(client)
        if found := _emulators(workers):
            return found
        if time.monotonic() >= deadline:
            raise CampaignError(refusal(address, len(workers), timeout_s))
        time.sleep(POLL_S)


def run_on_worker(entry: dict, key: str, topic: str, **options: object) -> RunOutcome:
    """`execute_entry` on a Dask worker, after telling the client (an event on `topic`) which
    worker took the try `key`: the scheduler's "processing" also counts tasks merely assigned."""
    worker = get_worker()
    worker.log_event(topic, {"key": key, "worker": worker.address, "host": socket.gethostname(), "pid": os.getpid()})
    return execute_entry(entry, None, **options)


def run_dask(
    entries: list[ManifestEntry],
    address: str,
    profile: str | None,
    retries: int,
    on_retry: Callable[[RunOutcome, int], None] | None = None,
    connect_timeout_s: float = CONNECT_S,
    extraction: Extraction = Extraction(),
    fidelity: str = "flag",
    mavlink_signing: bool = False,
    on_status: Callable[[str], None] | None = None,
    on_note: Callable[[str], None] | None = None,
) -> Iterator[RunOutcome]:
    """Submit every entry to the scheduler at `address` (tcp://HOST:8786); yield as they finish.

    `on_status` gets the queue in a few words at every look (queued, running); `on_note` one line
    whenever a run starts on a worker or moves to another one (its worker died).
    """
    with connect(address, connect_timeout_s) as client:
        if on_status:
            on_status(f"waiting for a worker with {RESOURCE}=1")
        await_emulators(client, address)
        tries = Retries(retries, on_retry)
        by_index = {e.index: e for e in entries}
        token = uuid.uuid4().hex[:8]
        topic = f"uavcas-campaign-{token}"
        started: deque[tuple[float, dict]] = deque()  # filled on the client's event loop
        client.subscribe_topic(topic, started.append)
        index_of: dict[str, int] = {}  # key of a try in flight -> run index
        where: dict[str, str] = {}  # key -> the worker running it (its last "started" event)

        def submit(e: ManifestEntry) -> Future:
            n = tries.started(e.index)
            key = f"uavcas-run-{e.index}-try{n}-{token}"
            fut = client.submit(run_on_worker, e.to_dict(), key, topic, profile=profile, return_files=True,
                                extraction=extraction, fidelity=fidelity, mavlink_signing=mavlink_signing,
                                detach=True, resources={RESOURCE: 1}, pure=False, key=key)
            index_of[key] = e.index
            return fut

        pending = [submit(e) for e in entries]
        lacking_since: float | None = None  # since when the cluster has had no emulator worker
        while pending:
            time.sleep(POLL_S)
            while started:
                msg = started.popleft()[1]
                key, worker = msg["key"], msg["worker"]
                if key in index_of and where.get(key) != worker:
                    verb = "moved to" if key in where else "started on"  # moved: Dask's retry, its worker died
                    if on_note:
                        on_note(f"run {index_of[key]} {verb} worker {worker} (host {msg['host']}, pid {msg['pid']})")
                    where[key] = worker
            for fut in [f for f in pending if f.done()]:
                pending.remove(fut)
                idx = index_of.pop(fut.key)
                try:
                    out: RunOutcome = fut.result()
                except Exception as exc:  # Dask gave up on the task (workers died), or it could not run at all
                    out = RunOutcome(index=idx, ok=False, host=where.get(fut.key, "?"), wall_s=0.0,
                                     error=f"dask: {_first_line(exc)}")
                where.pop(fut.key, None)
                fut.release()  # the shard bytes are in `out` now; the cluster may forget them
                if tries.again(out):
                    pending.append(submit(by_index[idx]))
                    continue
                yield out
            if on_status:
                on_status(f"queued {len(pending) - len(where)} running {len(where)}")
            workers = _workers(client)
            if _emulators(workers) or not pending:
                lacking_since = None
            elif lacking_since is None:
                lacking_since = time.monotonic()
            elif time.monotonic() - lacking_since > EMULATOR_WAIT_S:
                raise CampaignError(refusal(address, len(workers), EMULATOR_WAIT_S)
                                    + f"; {len(pending)} run(s) left unfinished")
