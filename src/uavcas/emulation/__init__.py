"""Realise a Plan on real Linux stacks: namespaces, a bridge fabric, per-link shaping.

Facts about the kernel behind the design: ../shared/docs/EMULATION-NOTES.md.

`Emulation` and `WindowReport` are in `uavcas.emulation.emulation`, not re-exported: the emulator
reads plans through the attack families, which import this package's modules (`kernel`, `apps`),
so this `__init__`, which Python runs first, must not lead back to them. The forwarding
computation, the node names and the queue limits are the pure network model, `uavcas.network`.
"""

from .cleanup import CleanReport, clean
from .fabric import SwitchPorts
from .probe import Features, probe
from .shaping import Shape, ShapingRecord, shaping_jsonl

__all__ = ["CleanReport", "Features", "Shape", "ShapingRecord", "SwitchPorts", "clean", "probe", "shaping_jsonl"]
