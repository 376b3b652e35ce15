"""Checking the emulator, apart from running it: `uavcas doctor` and what it is made of.

- `doctor`: the verdict (kernel features, a two-hop shaped path measured end to end, CPU
  contention), also `python -m uavcas.diagnostics.doctor` for a VM guest;
- `selftest`: the measurement endpoints started inside the namespaces;
- `checks`: their figures against the plan (tolerances, binomial loss interval);
- `contention`: how contended this machine's CPUs are over an interval;
- `vm`: the same self-test in a stock Debian kernel under QEMU (`uavcas doctor --vm`).

The runtime (`uavcas.emulation`) never imports this package; it imports the runtime. Nothing
is re-exported here on purpose: the endpoints and the guest run these modules with `python -m`,
and every import a package `__init__` adds is paid again by each of those processes (on an
emulated CPU, seconds).
"""
