"""A run that a test kills with SIGKILL: sets up, starts a process in a node, waits forever."""

from __future__ import annotations

import sys
import time

from uavcas.emulation.emulation import Emulation
from uavcas.testing.handmade_plans import link, nodes, plan, window

prefix = sys.argv[1]
p = plan(nodes(3), [window(0, [link("uav0", "uav1", 10, 2, 0.01), link("uav1", "uav2", 10, 2, 0.01)])])
emu = Emulation(p, prefix=prefix, cpu_cap=0.5)
emu.__enter__()
emu.apply_window(0)
child = emu.popen("uav1", ["sleep", "300"])
print(f"ready {child.pid}", flush=True)
time.sleep(300)
