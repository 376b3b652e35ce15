"""Routing by link quality over the benign plans of issue 12 (no root, ~10 s).

2 path-loss models x 4 missions x {10, 20} UAVs x seeds, 2 BSs, 10 dBm, 12 windows: how many
UAV -> BS routes cross a hop whose loss is >= 0.5 (target: none) and the share of UAV-windows the
routing marks disconnected (target: <= 10 %).

    .venv/bin/python benchmarks/routing_quality.py [--seeds 2] [--profile NAME|PATH]
"""

from __future__ import annotations

import argparse
import itertools

from uavcas.twin.plan import plan
from uavcas.twin.profile import load_profile


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--profile", default=None)
    args = ap.parse_args()
    prof = load_profile(args.profile)
    routes = dead = off = uav_windows = plans = 0
    by_model: dict[str, list[float]] = {}
    for pl, mission, n, seed in itertools.product(("logdist", "3gpp"), ("spiral", "grid", "hover_transit", "random"),
                                                  (10, 20), range(args.seeds)):
        p = plan(f"benign-{n}-2-image-{pl}-adaptive-{mission}-10-95", seed=seed, profile=prof)
        plans += 1
        for w in p.windows:
            loss = {(lk.a, lk.b): lk.loss for lk in w.links} | {(lk.b, lk.a): lk.loss for lk in w.links}
            for r in w.routes:
                routes += 1
                dead += any(loss[h] >= 0.5 for h in zip(r.hops, r.hops[1:]))
            off += len(p.disconnected_uavs(w))
        uav_windows += n * len(p.windows)
        by_model.setdefault(pl, []).append(p.disconnected_fraction)
    print(f"profile {prof.name}: {plans} plans, {routes} routes, {dead} over a hop with loss >= 0.5; "
          f"disconnected {off}/{uav_windows} UAV-windows = {off / uav_windows:.2%}")
    for pl, v in by_model.items():
        print(f"  {pl}: {sum(v) / len(v):.2%} disconnected (mean over plans)")


if __name__ == "__main__":
    main()
