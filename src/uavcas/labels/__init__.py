"""labels: ground truth of flows from a run's attack log (rules in `uavcas.labels.label`, the
per-family rules in `uavcas.attacks.<family>`)."""

from __future__ import annotations

from .attacklog import AttackLog, AttackWindow, Injection, LabelError, read_attack_log
from .label import LABEL_MODES, SOURCES, TruthContext, label_flows

__all__ = [
    "LABEL_MODES", "SOURCES", "AttackLog", "AttackWindow", "Injection", "LabelError", "TruthContext",
    "label_flows", "read_attack_log",
]  # fmt: skip
