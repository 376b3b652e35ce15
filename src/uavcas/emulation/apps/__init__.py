"""Real programs run inside an emulation's namespaces: attack tools, capture, and what every
process needs. (Benign traffic is `uavcas.traffic`, the apps a payload is composed of; the
fabric-side rules of attacks, e.g. the blackhole's nft table, live in `uavcas.attacks`.)

* `flood`     hping3 SYN flood with closed-loop rate calibration and an exact SYN counter;
* `replayer`  scapy replay process fed by a port mirror (run inside the attacker namespace);
* `mavinject` forged MAVLink COMMAND_LONG to a victim's autopilot (pymavlink, attacker namespace);
* `capture`   one tcpdump per switch, with its drop counters;
* `procs`     a supervised process: started in its own session, stopped by PID with a signal;
* `versions`  versions of the external tools, for run.json.
"""
