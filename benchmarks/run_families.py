"""20-UAV, 12-window run of every single-attack family: wall time, packets, drops, shaping.

    sudo .venv/bin/python benchmarks/run_families.py [--uavs 20] [--windows 12] [--out /tmp/uavcas-bench]
        [--families dos,ddos,blackhole,wormhole,replay] [--json results.json]

Runs one after another (timing features suffer when runs share the 2 cores). For each run:
wall time, packets captured and kernel drops over all switch captures, the shaper's applied vs
planned rate/delay/loss (read back from the kernel and the delay daemon, shaping.jsonl), the
delay daemon's scheduling lag, and the family's own evidence (SYN rate inside/outside the
logged window, blackhole drops, wormhole path, replay injections found in the pcaps).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from uavcas.testing import runcheck as rc

FAMILIES = {"dos": "dos=1000", "ddos": "ddos=1000", "blackhole": "blackhole", "wormhole": "wormhole",
            "replay": "replay=50,200,10,5,inc"}


def shaping_summary(path: Path) -> dict:
    recs = [json.loads(x) for x in path.read_text().splitlines() if x.strip()]
    rate_err = [abs(r["applied_rate_mbps"] / r["planned_rate_mbps"] - 1) for r in recs if r["applied_rate_mbps"]]
    delay_err = [abs(r["applied_delay_ms"] - r["planned_delay_ms"]) for r in recs if r["applied_delay_ms"] is not None]
    loss_err = [abs(r["applied_loss"] - r["planned_loss"]) for r in recs if r["applied_loss"] is not None]
    missing = sum(1 for r in recs if None in (r["applied_rate_mbps"], r["applied_delay_ms"], r["applied_loss"]))
    return {"records": len(recs), "missing_readback": missing,
            "planned_rate_mbps_mean": round(statistics.fmean(r["planned_rate_mbps"] for r in recs), 3) if recs
            else None,
            "applied_rate_mbps_mean": round(statistics.fmean(r["applied_rate_mbps"] for r in recs
                                                             if r["applied_rate_mbps"]), 3) if recs else None,
            "rate_rel_err_max": max(rate_err, default=None), "delay_abs_err_ms_max": max(delay_err, default=None),
            "loss_abs_err_max": max(loss_err, default=None),
            "planned_delay_ms_mean": round(statistics.fmean(r["planned_delay_ms"] for r in recs), 4) if recs else None,
            "planned_loss_max": max((r["planned_loss"] for r in recs), default=None)}


def measured_delay(run: Path, max_size: int = 100) -> dict:
    """Per-hop one-way delay measured from the captures vs the plan's delay (runcheck.hop_delays)."""
    plan = json.loads((run / "plan.json").read_text())
    planned: dict[tuple[str, str], list[float]] = {}
    for w in plan["windows"]:
        for lk in w["links"]:
            for k in ((lk["a"], lk["b"]), (lk["b"], lk["a"])):
                planned.setdefault(k, []).append(lk["delay_ms"])
    rows = []
    for k, dts in rc.hop_delays(run, max_size=max_size).items():
        if len(dts) >= 50:
            dts = sorted(dts)
            rows.append((statistics.fmean(planned[k]), 1000 * dts[len(dts) // 2], 1000 * dts[int(0.9 * len(dts))]))
    if not rows:
        return {}
    rel = sorted(m / p for p, m, _ in rows if p > 2.0)
    excess = sorted(m - p for p, m, _ in rows)
    return {"link_directions": len(rows), "planned_ms_mean": round(statistics.fmean(p for p, _, _ in rows), 3),
            "measured_median_ms_mean": round(statistics.fmean(m for _, m, _ in rows), 3),
            "measured_p90_ms_mean": round(statistics.fmean(q for _, _, q in rows), 3),
            "excess_ms_median": round(excess[len(excess) // 2], 3), "excess_ms_max": round(excess[-1], 3),
            "planned_ms_max": round(max(p for p, _, _ in rows), 3),
            "measured_over_planned_median_for_planned_gt_2ms": round(rel[len(rel) // 2], 3) if rel else None}


def evidence(run: Path, family: str) -> dict:
    log = rc.attack_log(run)
    w = rc.windows(run)
    until = rc.crossed(run)
    out: dict = {}
    for aid, (start, stop, rec) in w.items():
        out["window_s"] = round(stop - start, 3)
        if family in ("dos", "ddos"):
            pk = rc.read_pcap(run / "pcap" / f"s-{rec['victims'][0]}.pcap")
            out["syn"] = {}
            for ip in rec["attacker_ips"]:
                fc = rc.flood_check(pk, ip, rec["victim_ips"][0], start, stop, until=until.get(aid))
                out["syn"][ip] = {"inside": fc.inside, "outside": fc.outside, "pps": round(fc.pps, 1)}
            out["logged_rates"] = [r["measured_pps"] for r in log if r["event"] == "rate"]
        if family == "blackhole":
            out["dropped_frames"] = next(r.get("dropped_frames") for r in log if r["event"] == "stop")
        if family == "wormhole":
            out["paths"] = rec.get("paths")
            out["fdb_changes"] = rec.get("fdb_changes")
        if family == "replay":
            inj = [r for r in log if r["event"] == "inject"]
            seen = set()
            for f in (run / "pcap").glob("*.pcap"):
                seen |= {(x.src, x.dst, x.ip_id, x.ttl, x.seq) for x in rc.read_pcap(f) if x.ttl != 64}
            found = sum((r["src_ip"], r["dst_ip"], r["ip_id"], r["ttl"], r["seq"]) in seen for r in inj)
            out.update(injected=len(inj), found_in_pcaps=found,
                       replay_of_replay=sum(r["orig_ttl"] != 64 for r in inj))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--uavs", type=int, default=20)
    ap.add_argument("--bss", type=int, default=2)
    ap.add_argument("--windows", type=int, default=12)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=Path, default=Path("/tmp/uavcas-bench"))
    ap.add_argument("--families", default=",".join(FAMILIES))
    ap.add_argument("--pathloss", default="logdist")
    ap.add_argument("--tx-dbm", default="30")
    ap.add_argument("--mission", default="random")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    from uavcas.emulation.runner import realize
    from uavcas.fidelity import audit_run
    from uavcas.twin.plan import plan

    results = []
    for fam in args.families.split(","):
        config = (f"{FAMILIES[fam]}-{args.uavs}-{args.bss}-image-{args.pathloss}-adaptive-{args.mission}-"
                  f"{args.tx_dbm}-95")
        p = plan(config, seed=args.seed, windows=args.windows)
        t = time.monotonic()
        art = realize(p, args.out / f"{fam}-{args.pathloss}-{args.mission}-{args.tx_dbm}")
        if art.exit_status == 0:  # each run audited, as `uavcas run` does (the runner does not)
            art.run_info = audit_run(art.out_dir)
        wall = time.monotonic() - t
        info = art.run_info
        res = {"family": fam, "config": config, "exit_status": art.exit_status, "wall_s": round(wall, 2),
               "plan_s": p.duration_s, "setup_s": info["timings"].get("setup_s"),
               "packets_captured": info["packets_captured"], "capture_drops": info["capture_drops"],
               "pcap_mb": round(sum(c["size_bytes"] for c in info["capture"]) / 1e6, 1),
               "http_ok": sum(c["ok"] for c in info["http_clients"]),
               "http_failed": sum(c["failed"] for c in info["http_clients"]),
               "window_apply_ms_max": round(1000 * max(w["timings_s"]["total_s"] for w in info["window_applies"]), 1),
               "schedule_lateness_ms": info["timings"].get("schedule_lateness_ms"),
               "delay_daemon": {k: info["delay_daemon"].get(k) for k in ("packets", "overflows", "max_lag_us")}
               if info.get("delay_daemon") else None,
               "shaping": shaping_summary(art.shaping_path), "measured_delay": measured_delay(art.out_dir),
               "evidence": evidence(art.out_dir, fam)}
        results.append(res)
        print(json.dumps(res), flush=True)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
