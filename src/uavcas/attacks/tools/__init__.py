"""The attack families' tools: the programs and writers an executor runs, beside their families.

* `flood`       hping3 SYN flood, paced from outside at absolute deadlines, behind a gate (dos, ddos),
                with its `pacer` (one process per hping3);
* `replayer`    scapy replay process fed by a port mirror, in the attacker's namespace (replay);
* `mavinject`   forged MAVLink COMMAND_LONG to a victim's autopilot, in the attacker's namespace
                (mavlink_inject);
* `gps_spoofer` publishes a spoofer's [start, stop) to the victim's GPS receiver (gps_spoof).

A tool's process starts by its file's path (`tool_path`: `python FILE ARGS`), not as `python -m
uavcas.attacks.tools.TOOL`: a module of a package loads after its packages, and `uavcas.attacks`
loads every family (seconds on a busy host, per attacker, before t0), and a family that imports
its tool would have it loaded twice (once as a module, once as `__main__`). So a tool imports no
family, only what it needs (the pacer: nothing of uavcas). This package is no family
(`uavcas.attacks` skips it when it imports its modules); what a tool takes from the benign apps
(`uavcas.emulation.apps`: `procs`, the MAVLink specs and GPS receiver) it imports from there.
"""

from __future__ import annotations

from pathlib import Path


def tool_path(name: str) -> Path:
    """The file of the tool `name` (a module of this package), which an executor runs by its path."""
    path = Path(__file__).with_name(f"{name}.py")
    if name.startswith("_") or not path.is_file():
        raise ValueError(f"no attack tool {name!r} in {path.parent}")
    return path
