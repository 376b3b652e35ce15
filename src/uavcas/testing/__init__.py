"""Helpers shared by the test suite and the benchmarks (as `numpy.testing` is), so that neither
imports the other's files.

- `handmade_plans`: Plans built by hand for the emulator (exact links and routes, no planner draws).
- `runcheck`: a run directory read back with dpkt, independently of `uavcas.flows` (a second
  opinion on the captures). dpkt is not a runtime dependency: it comes with the `test` and
  `bench` extras.

Nothing in the rest of the package imports this one.
"""
