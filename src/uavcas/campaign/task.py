"""One campaign run, start to shard: plan -> run (real time, as root) -> extract -> label.

`execute_entry` is what a local job or a Dask worker executes. The emulation runs in a child
process (`uavcas run`), so a crash or a signal there is contained and cleaned up by the runner
itself, and several runs can proceed at once with their own namespace prefixes. The result is a
plain value (bytes and dicts), so it crosses a Dask connection unchanged.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from uavcas.scenario import ManifestEntry

# Small run files the client keeps for every run, wherever it ran (pcaps stay with the run).
RUN_FILES = ("plan.json", "run.json", "attacks.jsonl", "shaping.jsonl")
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
    files: dict[str, bytes] = field(default_factory=dict)  # RUN_FILES, when returned


def _tail(text: str, n: int = 400) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return (lines[-1] if lines else "")[-n:]


def execute_entry(
    entry: ManifestEntry | dict,
    run_dir: str | None = None,
    profile: str | None = None,
    view: str = "5tuple",
    labels: str = "ours",
    return_files: bool = False,
) -> RunOutcome:
    """Run one manifest entry into `run_dir` (a temporary directory when None) and extract it."""
    from uavcas.dataset.store import extract_run

    if isinstance(entry, dict):
        entry = ManifestEntry(**entry)
    t0 = time.monotonic()
    host = socket.gethostname()
    own_tmp = run_dir is None
    base = Path(run_dir) if run_dir else Path(tempfile.mkdtemp(prefix=f"uavcas-run{entry.index}-"))
    if base.exists() and not own_tmp:
        shutil.rmtree(base)
    out = RunOutcome(index=entry.index, ok=False, host=host, wall_s=0.0)
    cmd = [
        sys.executable, "-m", "uavcas.cli", "run", entry.config,
        "--seed", str(entry.seed), "--windows", str(entry.windows),
        "--window-s", repr(entry.window_s), "--out", str(base),
    ]
    if profile:
        cmd += ["--profile", profile]
    try:
        limit_s = entry.windows * entry.window_s + RUN_SLACK_S
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=limit_s, env=env)
        if proc.returncode != 0:
            out.error = f"uavcas run exited {proc.returncode}: {_tail(proc.stderr) or _tail(proc.stdout)}"
            return out
        with tempfile.TemporaryDirectory(prefix="uavcas-extract-") as ds:
            info = extract_run(base, Path(ds), view=view, labels=labels, run_id=str(entry.index))
            out.shard = (Path(ds) / "shards" / f"{info.run_id}.parquet").read_bytes()
            out.n_flows, out.class_counts = info.n_flows, dict(info.class_counts)
        if return_files:
            out.files = {n: (base / n).read_bytes() for n in RUN_FILES if (base / n).exists()}
        out.ok = True
        return out
    except subprocess.TimeoutExpired:
        out.error = f"uavcas run did not finish within {limit_s:.0f} s"
        return out
    except Exception as e:  # reported per run; the campaign goes on and retries
        out.error = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
        return out
    finally:
        out.wall_s = round(time.monotonic() - t0, 3)
        if own_tmp:
            shutil.rmtree(base, ignore_errors=True)


def outcome_summary(o: RunOutcome) -> dict:
    return {
        "index": o.index,
        "ok": o.ok,
        "host": o.host,
        "wall_s": o.wall_s,
        "n_flows": o.n_flows,
        "class_counts": o.class_counts,
        "error": o.error,
    }


def summary_json(o: RunOutcome) -> str:
    return json.dumps(outcome_summary(o), sort_keys=True)
