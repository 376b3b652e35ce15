"""One campaign run, start to shard: plan -> run (real time, as root) -> extract -> label.

`execute_entry` is what a local job or a Dask worker executes. The emulation runs in a child
process (`campaign.worker`), so a crash or a signal there is contained and cleaned up by the
runner itself, and several runs can proceed at once with their own namespace prefixes. The
result is a plain value (bytes and dicts), so it crosses a Dask connection unchanged.
"""

from __future__ import annotations

import io
import shutil
import socket
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from uavcas.rundir import RunDir
from uavcas.scenario import ManifestEntry

from .worker import WorkerRequest, realize_in_child

RUN_SLACK_S = 120.0  # set-up, tear-down and extraction on top of the scenario's own duration


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


def execute_entry(
    entry: ManifestEntry | dict,
    run_dir: str | None = None,
    profile: str | None = None,
    view: str = "5tuple",
    labels: str = "ours",
    return_files: bool = False,
    min_attack_fraction: float = 0.0,
    fidelity: str = "flag",
) -> RunOutcome:
    """Run one manifest entry into `run_dir` (a temporary directory when None) and extract it.

    `fidelity`: what a run whose fidelity audit failed becomes: "flag" (kept, its verdict in the
    dataset card) or "retry" (tried again like a failed run; the last try is kept, flagged).
    """
    import pyarrow.parquet as pq

    from uavcas.dataset.parquet import to_table
    from uavcas.extract import extract

    if isinstance(entry, dict):
        entry = ManifestEntry(**entry)
    t0 = time.monotonic()
    host = socket.gethostname()
    own_tmp = run_dir is None
    base = Path(run_dir) if run_dir else Path(tempfile.mkdtemp(prefix=f"uavcas-run{entry.index}-"))
    if base.exists() and not own_tmp:
        shutil.rmtree(base)
    out = RunOutcome(index=entry.index, ok=False, host=host, wall_s=0.0)
    req = WorkerRequest(config=entry.config, seed=entry.seed, windows=entry.windows, window_s=entry.window_s,
                        out_dir=str(base), profile=profile)
    try:
        res = realize_in_child(req, limit_s=entry.windows * entry.window_s + RUN_SLACK_S)
        if not res.ok:
            out.error = res.error
            return out
        shard = extract(base, view=view, labels=labels, run_id=str(entry.index),
                        min_attack_fraction=min_attack_fraction)
        buf = io.BytesIO()
        pq.write_table(to_table(shard.frame, meta=asdict(shard.info)), buf, compression="zstd")
        out.shard = buf.getvalue()
        out.n_flows, out.class_counts = shard.info.n_flows, dict(shard.info.class_counts)
        out.fidelity = shard.info.fidelity
        out.retry = fidelity == "retry" and out.fidelity == "fail"
        if return_files:
            out.files = {p.name: p.read_bytes() for p in RunDir(base).files() if p.exists()}
        out.ok = True
        return out
    except Exception as e:  # reported per run; the campaign goes on and retries
        out.error = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
        return out
    finally:
        out.wall_s = round(time.monotonic() - t0, 3)
        if own_tmp:
            shutil.rmtree(base, ignore_errors=True)
