"""Realise a Plan on real Linux stacks: namespaces, a bridge fabric, per-link shaping.

Facts about the kernel behind the design: ../shared/docs/EMULATION-NOTES.md.
"""

from .cleanup import CleanReport, clean
from .controller import Forwarding, compute
from .emulation import Emulation, WindowReport
from .fabric import SwitchPorts
from .naming import Naming, new_prefix
from .probe import Features, probe
from .shaping import Shape, ShapingRecord, shaping_jsonl

__all__ = ["CleanReport", "Emulation", "Features", "Forwarding", "Naming", "Shape", "ShapingRecord",
           "SwitchPorts", "WindowReport", "clean", "compute", "new_prefix", "probe",
           "shaping_jsonl"]
