"""fidelity.json beside a run, and its summary in run.json.

`audit_run` is stage 2b as the run command and the campaign worker make it, after `realize`: the
runner itself does not audit, so the kernel package does not import this one."""

from __future__ import annotations

from pathlib import Path

from uavcas.atomic import atomic_write_text
from uavcas.flows.packets import PacketTable
from uavcas.rundir import FidelitySummary, RunDir, RunDirError, RunInfo

from .audit import audit
from .model import Fidelity, Tolerances, summary


def write_fidelity(run_dir: str | Path, tolerances: Tolerances | None = None,
                   table: PacketTable | None = None) -> Fidelity:
    """Audit a run, write RUN_DIR/fidelity.json and put its summary in run.json (if there is one)."""
    rd = RunDir(Path(run_dir))
    f = audit(rd.root, tolerances, table)
    atomic_write_text(rd.fidelity_json, f.to_json())
    _set_summary(rd, summary(f))
    return f


def audit_run(run_dir: str | Path) -> RunInfo | None:
    """Audit a run that finished (default tolerances for its swarm): `write_fidelity`, or, where the
    audit cannot be made, the error in run.json (verdict "error"); the run itself is kept either
    way. Returns the run.json it leaves (None where there is none)."""
    try:
        write_fidelity(run_dir)
    except Exception as e:  # the run itself succeeded: keep it, and say the audit could not be made
        record_audit_error(run_dir, f"{type(e).__name__}: {e}")
    return RunDir(Path(run_dir)).read_info()


def record_audit_error(run_dir: str | Path, error: str) -> None:
    """The audit could not be made: say so in run.json (verdict "error") instead of a verdict."""
    _set_summary(RunDir(Path(run_dir)), FidelitySummary(verdict="error", failed=[], error=error[:400]))


def _set_summary(rd: RunDir, s: FidelitySummary) -> None:
    info = rd.read_info()
    if info is not None:
        atomic_write_text(rd.run_json, info.model_copy(update={"fidelity": s}).to_json())


def read_fidelity(run_dir: str | Path) -> Fidelity | None:
    """RUN_DIR/fidelity.json, or None when the run was never audited."""
    rd = RunDir(Path(run_dir))
    if not rd.fidelity_json.exists():
        return None
    try:
        return Fidelity.model_validate_json(rd.fidelity_json.read_text())
    except ValueError as exc:
        raise RunDirError(f"{rd.fidelity_json}: invalid ({str(exc).splitlines()[0]})") from None
