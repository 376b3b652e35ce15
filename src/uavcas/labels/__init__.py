"""labels: ground truth of flows from a run's attack log (rules in `uavcas.labels.label`)."""

from __future__ import annotations

from .attacklog import AttackLog, AttackWindow, Injection, LabelError, read_attack_log
from .label import LABEL_MODES, REPLAY_MATCH_TOLERANCE_S, SOURCES, label_flows

__all__ = [
    "LABEL_MODES", "REPLAY_MATCH_TOLERANCE_S", "SOURCES", "AttackLog", "AttackWindow", "Injection",
    "LabelError", "label_flows", "read_attack_log",
]  # fmt: skip
