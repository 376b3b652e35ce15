"""labels: ground truth of packets and flows from a run's attack log.

Per packet (`effects`): one effect each, from the families' rules (`uavcas.attacks.<family>`) and the
packet follower; per flow (`label`): the labels its packets' effects give. Only the attack log's
values are re-exported here: `effects` and `label` run the families' rules, and the families import
`attacklog`, so this `__init__`, which Python runs first, must not lead back to them.
"""

from __future__ import annotations

from .attacklog import AttackLog, AttackWindow, Injection, LabelError, read_attack_log

__all__ = ["AttackLog", "AttackWindow", "Injection", "LabelError", "read_attack_log"]
