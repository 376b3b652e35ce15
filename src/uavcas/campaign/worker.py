"""The campaign's emulation worker: one scenario realised in a child process, a typed result back.

`realize_in_child(request)` starts `python -m uavcas.campaign.worker REQUEST RESULT` and reads the
`WorkerResult` it writes. A separate interpreter (not the CLI, not a multiprocessing child)
because Dask workers run as daemonic processes, which multiprocessing forbids to have children,
and because a crash or a signal in the emulation must not take the campaign down: the child's
own runner tears its namespaces down on SIGTERM, and a child that dies without a result still
yields a failed `WorkerResult` naming its exit status.

The child never outlives the thread that started it holding namespaces: it asks the kernel for
SIGTERM when that thread's process dies (`PR_SET_PDEATHSIG`), and on a Dask worker it runs in its
own session (`detach`), so that killing the worker's whole process group (SIGKILL, which no
teardown survives) leaves it that SIGTERM, and its runner tears its namespaces down.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

from pydantic import BaseModel, ConfigDict, ValidationError

from uavcas.atomic import atomic_write_text
from uavcas.emulation.preflight import preflight, probe_kernel
from uavcas.emulation.runner import RunOptions, realize
from uavcas.fidelity import audit_run
from uavcas.twin.plan import plan

TERM_GRACE_S = 30.0  # after SIGTERM, the child's teardown gets this long before SIGKILL
PARENT_ENV = "UAVCAS_WORKER_PARENT"  # the PID the child is to die with (see `_die_with_parent`)
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


class WorkerRequest(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    config: str
    seed: int
    windows: int
    window_s: float
    rounds: int = 1
    out_dir: str
    profile: str | None = None
    mavlink_signing: bool = False  # RunOptions.mavlink_signing


class WorkerResult(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    ok: bool
    exit_status: int  # the runner's (0 ok); 2 when the run could not start
    error: str = ""  # one line when not ok


def realize_request(req: WorkerRequest) -> WorkerResult:
    """Plan, check, realise and audit one scenario into `req.out_dir` (in this process; needs root).
    The audit's verdict in run.json is what the campaign's fidelity policy reads (`task.execute_entry`)."""
    p = plan(req.config, seed=req.seed, windows=req.windows, window_s=req.window_s, profile=req.profile,
             rounds=req.rounds)
    out = Path(req.out_dir)
    reason = preflight(p, out)
    feats = None
    if reason is None:
        feats, reason = probe_kernel()
    if reason:
        return WorkerResult(ok=False, exit_status=2, error=reason)
    art = realize(p, out, RunOptions(mavlink_signing=req.mavlink_signing), features=feats)
    if art.exit_status == 0:  # stage 2b, as `uavcas run` makes it: fidelity.json and its summary in run.json
        audit_run(art.out_dir)
    return WorkerResult(ok=art.exit_status == 0, exit_status=art.exit_status,
                        error="" if art.exit_status == 0 else f"run exited {art.exit_status}: {art.exit_reason}")


def _one_line(e: BaseException) -> str:
    text = str(e).strip().splitlines()
    return f"{type(e).__name__}: {text[0] if text else ''}"[:400]


def _tail(text: str, n: int = 400) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return (lines[-1] if lines else "")[-n:]


def realize_in_child(req: WorkerRequest, limit_s: float, detach: bool = False) -> WorkerResult:
    """`realize_request` in a child interpreter, at most `limit_s` seconds (then SIGTERM, SIGKILL).

    `detach`: the child gets its own session (a Dask worker's run: see the module's docstring). A
    local campaign keeps it in the terminal's process group, where Ctrl-C reaches it directly.
    """
    with tempfile.TemporaryDirectory(prefix="uavcas-worker-") as tmp:
        req_path, res_path = Path(tmp) / "request.json", Path(tmp) / "result.json"
        req_path.write_text(req.model_dump_json())
        env = {**os.environ, "PYTHONUNBUFFERED": "1", PARENT_ENV: str(os.getpid())}
        proc = subprocess.Popen([sys.executable, "-m", "uavcas.campaign.worker", str(req_path), str(res_path)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env,
                                start_new_session=detach)
        try:
            _, err = proc.communicate(timeout=limit_s)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.communicate(timeout=TERM_GRACE_S)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.communicate()
            return WorkerResult(ok=False, exit_status=124, error=f"run did not finish within {limit_s:.0f} s")
        if not res_path.exists():
            return WorkerResult(ok=False, exit_status=proc.returncode or 1,
                                error=f"worker exited {proc.returncode} without a result: {_tail(err or '')}")
        try:
            return WorkerResult.model_validate_json(res_path.read_text())
        except ValidationError as e:
            return WorkerResult(ok=False, exit_status=1, error=f"worker result unreadable: {_one_line(e)}")


def _die_with_parent() -> None:
    """SIGTERM to this process when its parent dies (set here, not in a `preexec_fn`, which is
    unsafe in the parent's threads); a parent already gone by now is noticed and obeyed at once."""
    parent = os.environ.get(PARENT_ENV)
    if parent is None:  # run by hand: no parent to die with
        return
    libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
    if libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_PDEATHSIG)")
    if os.getppid() != int(parent):
        raise SystemExit(128 + signal.SIGTERM)


def main(argv: list[str] | None = None) -> int:
    req_path, res_path = (argv if argv is not None else sys.argv[1:])[:2]
    _die_with_parent()
    try:
        res = realize_request(WorkerRequest.model_validate_json(Path(req_path).read_text()))
    except BaseException as e:  # SystemExit from a signal included: the result says why
        res = WorkerResult(ok=False, exit_status=e.code if isinstance(e, SystemExit) and isinstance(e.code, int)
                           else 1, error=_one_line(e))
    atomic_write_text(Path(res_path), res.model_dump_json())
    return 0 if res.ok else 1


if __name__ == "__main__":
    sys.exit(main())
