"""How many flows could an attack's class hold at most? Labelled flows against that bound.

For a family that acts on its victim's traffic (all but jamming, which acts on every link its jammer
reaches), a flow can hold a packet of an attack on victim V in [start, stop) only if it touches V and its
time span overlaps [start, stop). That count bounds the class from above, whatever the truth rule,
under the flow definition (`uavcas.flows.termination`). Issue 23 used it to show that a payload
with more packets cannot give a stealth class more flows than its victim has connections and
streams during the attack (docs/measurements.md, stop 22).

usage: python benchmarks/attack_flow_bound.py RUN_DIR DATASET_DIR [RUN_DIR DATASET_DIR ...]
(DATASET_DIR: `uavcas extract RUN_DIR --out DATASET_DIR`, 5-tuple view)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pandas as pd

from uavcas.vocabulary import FAMILY_CLASS


def bound(run_dir: Path, dataset_dir: Path) -> dict:
    flows = pd.read_parquet(dataset_dir / "flows.parquet")
    events = [json.loads(line) for line in (run_dir / "attacks.jsonl").read_text().splitlines() if line.strip()]
    starts = {e["attack_id"]: e for e in events if e["event"] == "start"}
    stops = {e["attack_id"]: e["t_unix"] for e in events if e["event"] == "stop"}
    out = {}
    for family in sorted({e["family"] for e in starts.values()}):
        could = pd.Series(False, index=flows.index)
        for aid, s in starts.items():
            if s["family"] != family:
                continue
            victims = set(s["victim_ips"])
            touches = flows.src_ip.isin(victims) | flows.dst_ip.isin(victims)
            could |= touches & (flows.first_ts < stops[aid]) & (flows.last_ts >= s["t_unix"])
        labelled = flows.label.str.split("+").apply(lambda parts: FAMILY_CLASS[family] in parts)
        affected = flows[f"attack_packets_{family}"]
        out[family] = {
            "labelled": int(labelled.sum()), "bound": int(could.sum()),
            "bound_by_protocol": {int(k): int(v) for k, v in flows[could].protocol.value_counts().items()},
            "affected_packets": int(affected.sum()),
            "every_labelled_flow_holds_one": bool((affected[labelled] > 0).all()),
        }
    return out


def main(argv: list[str]) -> int:
    if not argv or len(argv) % 2:
        print(__doc__.strip().splitlines()[-2], file=sys.stderr)
        return 2
    for run, ds in zip(argv[::2], argv[1::2]):
        print(json.dumps({"run": run, **bound(Path(run), Path(ds))}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
