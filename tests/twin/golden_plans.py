"""Write tests/twin/data/plan_digests.json: the SHA-256 of plan.json of the quick preset's runs and
of the paper manifest's first 50 configurations (campaign seed 0, each run's own seed, as
`uavcas campaign` plans them). A change to the twin that moves any of them must say why (the
test names the configurations that moved); rewrite the file only for such a reasoned change:

    PYTHONPATH=src python tests/twin/golden_plans.py

Rewritten for schema 5 (Plan.mavlink_stream_hz, the MAVLink stream rate the plan records): every
one of the 56 plans was checked to be byte-identical to its schema-4 bytes once the new
`"mavlink_stream_hz": 4` line is removed and `"schema_version": 5` reads 4 again, so positions,
links, routes and attacks did not move.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from uavcas.scenario import manifest
from uavcas.twin.plan import plan

OUT = Path(__file__).resolve().parent / "data" / "plan_digests.json"


def digests() -> dict[str, str]:
    entries = manifest("quick", seed=0) + manifest("paper", seed=0)[:50]
    out = {}
    for e in entries:
        p = plan(e.config, seed=e.seed, windows=e.windows, window_s=e.window_s, rounds=e.rounds)
        out[f"{e.config}@{e.seed}"] = hashlib.sha256(p.to_json().encode()).hexdigest()
    return out


if __name__ == "__main__":
    OUT.write_text(json.dumps(digests(), indent=1, sort_keys=True) + "\n")
    print(f"wrote {OUT}")
