"""labels: ground truth of packets and flows from a run's attack log.

Per packet (`effects`): one effect each, from the families' rules (`uavcas.attacks.<family>`) and the
packet follower; per flow (`label`): the labels its packets' effects give.
"""

from __future__ import annotations

from .attacklog import AttackLog, AttackWindow, Injection, LabelError, read_attack_log
from .effects import PacketTruth, TruthContext, packet_truth
from .label import LABEL_MODES, SOURCES, Labelled, constructed_truth, label_flows, rule_text, truth_columns

__all__ = [
    "LABEL_MODES", "SOURCES", "AttackLog", "AttackWindow", "Injection", "LabelError", "Labelled", "PacketTruth",
    "TruthContext", "constructed_truth", "label_flows", "packet_truth", "read_attack_log", "rule_text", "truth_columns",
]  # fmt: skip
