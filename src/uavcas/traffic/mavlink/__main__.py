"""python -m uavcas.traffic.mavlink {uav|gcs} SPEC.json: one endpoint, until its deadline."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .autopilot import run_uav
from .ground import run_gcs
from .specs import GcsSpec, UavSpec


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m uavcas.traffic.mavlink")
    ap.add_argument("role", choices=("uav", "gcs"))
    ap.add_argument("spec", type=Path, help="the endpoint's spec (JSON)")
    a = ap.parse_args(argv)
    try:
        text = a.spec.read_text()
        spec = UavSpec.model_validate_json(text) if a.role == "uav" else GcsSpec.model_validate_json(text)
    except (OSError, ValueError) as e:
        print(f"mavlink {a.role}: bad spec {a.spec}: {str(e).splitlines()[0]}", file=sys.stderr)
        return 2
    try:
        summary = run_uav(spec) if a.role == "uav" else run_gcs(spec)
    except (OSError, TimeoutError) as e:
        print(f"mavlink {a.role} {spec.name}: {e}", file=sys.stderr)
        return 1
    print(json.dumps(summary), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
