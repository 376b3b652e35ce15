"""The attack families' tools: the programs and writers an executor runs, beside their families.

* `flood`       hping3 SYN flood, paced from outside at absolute deadlines, behind a gate (dos, ddos),
                with its `pacer` (one process per hping3);
* `replayer`    scapy replay process fed by a port mirror, in the attacker's namespace (replay);
* `mavinject`   forged MAVLink COMMAND_LONG to a victim's autopilot, in the attacker's namespace
                (mavlink_inject);
* `gps_spoofer` publishes a spoofer's [start, stop) to the victim's GPS receiver (gps_spoof).

Processes start as `python -m uavcas.attacks.tools TOOL ARGS` (`__main__`; the pacer, which needs
no package, by its file's path: `pacer.py` says why). The families import
their tools, and `uavcas.attacks` imports every family, so `python -m uavcas.attacks.tools.TOOL`
would load the tool twice (once as a module, once as `__main__`). This package is no family
(`uavcas.attacks` skips it when it imports its modules); what a tool takes from the benign
apps (`uavcas.emulation.apps`: `procs`, the MAVLink specs and GPS receiver) it imports from there.
"""
