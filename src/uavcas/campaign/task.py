"""One campaign run, start to shard: plan -> run (real time, as root) -> extract -> label.

`execute_entry` is what a local job or a Dask worker executes. The emulation runs in a child
process (`campaign.worker`), so a crash or a signal there is contained and cleaned up by the
runner itself, and several runs can proceed at once with their own namespace prefixes. The
result is a plain value (bytes and dicts), so it crosses a Dask connection unchanged.
"""

from __future__ import annotations

import io
import logging
import os
import shutil
import socket
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from uavcas.dataset.parquet import write_shard
from uavcas.emulation.cleanup import reclaim_dead
from uavcas.extract import extract
from uavcas.flows import TERMINATIONS
from uavcas.flows.assemble import DEFAULT_TERMINATION, HOST_VIEWS
from uavcas.flows.standards import DEFAULT_STANDARD
from uavcas.flows.standards import names as standard_names
from uavcas.rundir import RunDir
from uavcas.scenario import ManifestEntry
from uavcas.views import names as view_names
from uavcas.views import view

from .worker import WorkerRequest, realize_in_child

RUN_SLACK_S = 120.0  # set-up, tear-down and extraction on top of the scenario's own duration

# A Dask worker shows these with DASK_LOGGING__UAVCAS=info: one "starting" line per try of a run
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Extraction:
    """How every run of a campaign is extracted (`uavcas.extract.extract`'s options): one value,
    recorded with the campaign so that a resumed campaign cannot mix two kinds of rows."""

    view: str = "5tuple"
    termination: str | None = None  # None: the view's default (`uavcas.flows.termination`)
    labels: str = "ours"
    min_attack_fraction: float = 0.0
    features: str = DEFAULT_STANDARD  # the feature standard (`uavcas.flows.standards`)

    def __post_init__(self) -> None:
        if self.view not in view_names():
            raise ValueError(f"--view: {self.view!r} is not one of {', '.join(view_names())}")
        if self.features not in standard_names():
            raise ValueError(f"--features: {self.features!r} is not one of {', '.join(standard_names())}")
        if self.termination is not None and self.termination not in TERMINATIONS:
            raise ValueError(f"--termination: {self.termination!r} is not one of {', '.join(TERMINATIONS)}")
        if self.termination is not None and view(self.view).flow_key in HOST_VIEWS:
            raise ValueError(f"--termination: the {self.view} view has no termination policy")

    @property
    def policy(self) -> str | None:
        """The termination policy in force (None for the host-pair views, which have none)."""
        return None if view(self.view).flow_key in HOST_VIEWS else self.termination or DEFAULT_TERMINATION

    def options(self) -> dict:
        return {"view": self.view, "termination": self.termination, "labels": self.labels,
                "min_attack_fraction": self.min_attack_fraction, "features": self.features}


@dataclass
class RunOutcome:
    index: int
    ok: bool
    host: str
    wall_s: float
    error: str = ""
    shard: bytes = b""  # the run's flows as Parquet (run_id = campaign index)
    n_flows: int = 0
    class_counts: dict[str, int] = field(default_factory=dict)
    files: dict[str, bytes] = field(default_factory=dict)  # RunDir.FILES, when returned
    fidelity: str | None = None  # the run's fidelity verdict (pass, fail, error; None: not audited)
    retry: bool = False  # a finished run to try again (its fidelity failed and the policy retries)

    def summary(self) -> dict:
        """outcome.json: everything but the bytes."""
        d = asdict(self)
        del d["shard"], d["files"]
        return d


def extract_outcome(out: RunOutcome, run_dir: Path, extraction: Extraction = Extraction(), fidelity: str = "flag",
                    return_files: bool = False) -> RunOutcome:
    """Extract a finished run into `out` (ok): its shard as Parquet bytes (the one shard writer,
    `uavcas.dataset.parquet.write_shard`, so its feature standard and view are the shard's own),
    counts, verdict and, when `return_files`, its files."""
    shard = extract(run_dir, run_id=str(out.index), **extraction.options())
    buf = io.BytesIO()
    write_shard(shard.frame, asdict(shard.info), buf)
    out.shard = buf.getvalue()
    out.n_flows, out.class_counts = shard.info.n_flows, dict(shard.info.class_counts)
    out.fidelity = shard.info.fidelity
    out.retry = fidelity == "retry" and out.fidelity == "fail"
    if return_files:
        out.files = {p.name: p.read_bytes() for p in RunDir(run_dir).files() if p.exists()}
    out.ok = True
    return out


def execute_entry(
    entry: ManifestEntry | dict,
    run_dir: str | None = None,
    profile: str | None = None,
    extraction: Extraction = Extraction(),
    return_files: bool = False,
    fidelity: str = "flag",
    mavlink_signing: bool = False,
    detach: bool = False,
) -> RunOutcome:
    """Run one manifest entry into `run_dir` (a temporary directory when None) and extract it.

    `fidelity`: what a run whose fidelity audit failed becomes: "flag" (kept, its verdict in the
    dataset card) or "retry" (tried again like a failed run; the last try is kept, flagged).
    `detach`: the run's child in its own session (a Dask worker: `worker.realize_in_child`).
    Namespaces of runs on this host whose process died without teardown are removed first.
    """

    if isinstance(entry, dict):
        entry = ManifestEntry.from_dict(entry)
    t0 = time.monotonic()
    host = socket.gethostname()
    log.info("run %d starting on %s (pid %d): %s seed %d", entry.index, host, os.getpid(), entry.config, entry.seed)
    if os.geteuid() == 0:
        for rep in reclaim_dead():
            log.warning("run %d: removed what dead run %s left: %d namespace(s)%s", entry.index, rep.prefix,
                        len(rep.namespaces), f" ({rep.error})" if rep.error else "")
    own_tmp = run_dir is None
    base = Path(run_dir) if run_dir else Path(tempfile.mkdtemp(prefix=f"uavcas-run{entry.index}-"))
    if base.exists() and not own_tmp:
        shutil.rmtree(base)
    out = RunOutcome(index=entry.index, ok=False, host=host, wall_s=0.0)
    req = WorkerRequest(config=entry.config, seed=entry.seed, windows=entry.windows, window_s=entry.window_s,
                        rounds=entry.rounds, out_dir=str(base), profile=profile, mavlink_signing=mavlink_signing)
    try:
        res = realize_in_child(req, limit_s=entry.windows * entry.window_s + RUN_SLACK_S, detach=detach)
        if not res.ok:
            out.error = res.error
            return out
        return extract_outcome(out, base, extraction, fidelity, return_files)
    except Exception as e:  # reported per run; the campaign goes on and retries
        out.error = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
        return out
    finally:
        out.wall_s = round(time.monotonic() - t0, 3)
        if own_tmp:
            shutil.rmtree(base, ignore_errors=True)
