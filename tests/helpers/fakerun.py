"""A stand-in for `emulation.runner.realize` that needs no root: it writes fidsynth's synthetic run
(a chain uav0 - uav1 - bs0 whose emulator is the audit's own FIFO model, so its audit passes)
into the run directory and returns what the runner would. For the callers that audit after the
runner (`uavcas run`, the campaign worker)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from helpers.fidsynth import T0, Traffic, build, plan, run_info
from uavcas.emulation.runner import RunArtifacts


def realize_stub(exit_status: int = 0) -> Callable[..., RunArtifacts]:
    """A `realize` whose runs end with `exit_status` (0: finished; else failed, e.g. 1)."""
    reason = "ok" if exit_status == 0 else "RuntimeError: stub"

    def realize(p, out_dir, options=None, on_event=None, features=None) -> RunArtifacts:
        tr = Traffic()
        for k in range(80):
            tr.add(0.1 + k * 0.004, 600)
        rd = build(Path(out_dir), plan(), tr, info=run_info(exit_status=exit_status, exit_reason=reason))
        return RunArtifacts(rd.root, T0, 11.0, exit_status, reason, pcaps=rd.pcaps(), run_info=rd.read_info())

    return realize
