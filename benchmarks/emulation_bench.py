"""Emulation core benchmark: fabric setup/teardown, per-window reconfiguration, delay-stage throughput.

    sudo .venv/bin/python benchmarks/emulation_bench.py [--json out.json] [--quick]

Targets on this machine (2 vCPUs): setup <= 1 s and teardown <= 1 s for the 20-UAV + 2-BS full
mesh (231 switch links pre-created), reconfiguration <= 100 ms per window at 20 UAVs.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
from uavcas.atomic import atomic_write_text
from uavcas.diagnostics import selftest
from uavcas.emulation import kernel
from uavcas.emulation.emulation import Emulation
from uavcas.network.naming import new_prefix
from uavcas.testing.handmade_plans import link, nn_plan, nodes, plan, random_plan, window


def _wait_gone(prefix: str, timeout_s: float = 10.0) -> float:
    """Seconds until the kernel has really destroyed the run's namespaces (async cleanup_net)."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout_s:
        if not any(ns.startswith(prefix + "-") for ns in kernel.netns_list()):
            break
        time.sleep(0.01)
    return time.perf_counter() - t0


def bench_setup_teardown(repeats: int) -> dict:
    p = random_plan(20, 2, 1, seed=7)
    setups, teardowns, detail = [], [], []
    for _ in range(repeats):
        emu = Emulation(p, prefix=new_prefix(), links="all", readback=False)
        t0 = time.perf_counter()
        st = emu.setup()
        setups.append(time.perf_counter() - t0)
        t1 = time.perf_counter()
        emu.teardown()
        teardowns.append(time.perf_counter() - t1)
        detail.append(st)
        time.sleep(0.5)  # let the kernel finish destroying the veths before the next round
    return {"nodes": 22, "links_precreated": 231, "setup_s": _stats(setups), "teardown_s": _stats(teardowns),
            "setup_stages_s": {k: round(v, 4) for k, v in detail[-1].items()}}


def bench_windows(n_uav: int, n_windows: int, sparse: bool, links_mode: str) -> dict:
    p = nn_plan(n_uav, 2, n_windows, seed=3) if sparse else random_plan(n_uav, 2, n_windows, seed=3)
    emu = Emulation(p, prefix=new_prefix(), links=links_mode)
    try:
        t0 = time.perf_counter()
        emu.setup()
        setup = time.perf_counter() - t0
        reports = [emu.apply_window(i) for i in range(n_windows)]
    finally:
        emu.teardown()
    steady = reports[1:]  # window 0 brings everything up from nothing
    return {"nodes": n_uav + 2, "links_mode": links_mode, "windows": n_windows,
            "links_per_window": round(statistics.mean(len(w.links) for w in p.windows), 1),
            "reconfig_s": _stats([r.total_s for r in steady]),
            "first_window_s": round(reports[0].total_s, 4),
            "readback_s": _stats([r.timings_s.get("readback_s", 0.0) for r in steady]),
            "stages_s_median": {k: round(statistics.median(r.timings_s.get(k, 0.0) for r in steady), 4)
                                for k in ("create_s", "compute_s", "phase1_s", "delay_s", "phase2_s")},
            "links_toggled_median": statistics.median(r.links_up + r.links_down for r in steady),
            "fdb_changes_median": statistics.median(r.fdb_changes for r in steady), "setup_s": round(setup, 3)}


def bench_delay_stage(rates_pps: list[int], delay_ms: float = 1.0, seconds: float = 1.5) -> dict:
    p = plan(nodes(2), [window(0, [link("uav0", "uav1", 1000.0, delay_ms, 0.0)])])
    rows = []
    with Emulation(p, prefix=new_prefix()) as emu:
        emu.apply_window(0)
        for pps in rates_pps:
            r = selftest.measure_udp(emu, "uav0", "uav1", int(pps * seconds), pps, size=64)
            d = r["delays_ms"]
            rows.append({"offered_pps": pps, "achieved_pps": round(r["offered_pps"]), "loss": round(r["loss"], 4),
                         "delay_median_ms": round(d.get("median", float("nan")), 3),
                         "delay_p99_ms": round(d.get("p99", float("nan")), 3)})
        stats = emu.shaper.daemon_stats() if hasattr(emu.shaper, "daemon_stats") else {}
    limit = next((r["offered_pps"] for r in rows
                  if r["loss"] > 0.01 or r["delay_p99_ms"] > delay_ms + 2.0), None)
    return {"delay_ms": delay_ms, "rows": rows, "first_pps_dropping_or_lagging": limit, "daemon": stats}


def _stats(xs: list[float]) -> dict:
    return {"median": round(statistics.median(xs), 4), "min": round(min(xs), 4), "max": round(max(xs), 4), "n": len(xs)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path)
    ap.add_argument("--quick", action="store_true", help="fewer repeats and rates")
    a = ap.parse_args()
    res = {"setup_teardown_22": bench_setup_teardown(2 if a.quick else 5)}
    print(json.dumps(res, indent=1), flush=True)
    res["reconfig_22_full_mesh"] = bench_windows(20, 6 if a.quick else 12, sparse=False, links_mode="all")
    print(json.dumps(res["reconfig_22_full_mesh"], indent=1), flush=True)
    res["reconfig_22_plan_like"] = bench_windows(20, 6 if a.quick else 12, sparse=True, links_mode="plan")
    print(json.dumps(res["reconfig_22_plan_like"], indent=1), flush=True)
    res["reconfig_102_plan_like_lazy"] = bench_windows(100, 6 if a.quick else 12, sparse=True, links_mode="lazy")
    print(json.dumps(res["reconfig_102_plan_like_lazy"], indent=1), flush=True)
    rates = [5000, 10000, 20000] if a.quick else [2000, 5000, 10000, 15000, 20000, 30000, 40000]
    res["delay_stage"] = bench_delay_stage(rates)
    print(json.dumps(res["delay_stage"], indent=1), flush=True)
    if a.json:
        atomic_write_text(a.json, json.dumps(res, indent=1) + "\n")


if __name__ == "__main__":
    main()
