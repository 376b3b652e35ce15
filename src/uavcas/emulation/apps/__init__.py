"""Real programs run inside an emulation's namespaces: capture, and what every process needs.
(Benign traffic is `uavcas.traffic`, the apps a payload is composed of; the attack tools live
beside their families, `uavcas.attacks.tools`; the fabric-side rules of attacks, e.g. the
blackhole's nft table, in the families' modules.)

* `capture`   one tcpdump per switch, with its drop counters;
* `procs`     a supervised process: started in its own session, stopped by PID with a signal;
* `versions`  versions of the external tools, for run.json.
"""
