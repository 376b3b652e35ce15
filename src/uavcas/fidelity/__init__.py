"""The per-run fidelity audit: every packet followed switch by switch and held to the plan.

`audit(run_dir) -> Fidelity` (audit.py) measures against the FIFO model of the plan (fifo.py);
`write_fidelity` (store.py) writes RUN_DIR/fidelity.json and its summary in run.json, and
`audit_run` is that for a finished run as `uavcas run` and the campaign worker call it after
`realize` (an audit that fails is recorded, the run kept); the file's types and the tolerances
are in model.py.
"""

from __future__ import annotations

from .audit import audit
from .model import Fidelity, Tolerances, summary
from .store import audit_run, read_fidelity, record_audit_error, write_fidelity

__all__ = ["Fidelity", "Tolerances", "audit", "audit_run", "read_fidelity", "record_audit_error", "summary",
           "write_fidelity"]
