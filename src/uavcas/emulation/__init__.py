"""Realise a Plan on real Linux stacks: namespaces, a bridge fabric, per-link shaping.

Facts about the kernel behind the design: ../shared/docs/EMULATION-NOTES.md.

`Emulation` and `WindowReport` are in `uavcas.emulation.emulation`, not re-exported: the emulator
reads plans through the attack families, which import this package's modules (`kernel`, `naming`,
`apps`), so this `__init__`, which Python runs first, must not lead back to them.
"""

from .cleanup import CleanReport, clean
from .controller import Forwarding, compute
from .fabric import SwitchPorts
from .naming import Naming, new_prefix
from .probe import Features, probe
from .shaping import Shape, ShapingRecord, shaping_jsonl

__all__ = ["CleanReport", "Features", "Forwarding", "Naming", "Shape", "ShapingRecord", "SwitchPorts", "clean",
           "compute", "new_prefix", "probe", "shaping_jsonl"]
