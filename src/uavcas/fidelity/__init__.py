"""The per-run fidelity audit: every packet followed switch by switch and held to the plan.

`audit(run_dir) -> Fidelity` (audit.py) measures; `write_fidelity` writes RUN_DIR/fidelity.json
and the summary in run.json; the FIFO model of a link is fifo.py, the file's types model.py.
"""

from __future__ import annotations

from .audit import audit
from .model import Fidelity, FidelitySummary, Tolerances

__all__ = ["Fidelity", "FidelitySummary", "Tolerances", "audit"]
