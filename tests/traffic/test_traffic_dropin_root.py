"""A dropped-in traffic app's payload emulated for real (root): see test_traffic_dropin.py for the
app (`helpers.traffic_dropin`: a TCP echo server per BS, a client per UAV)."""

from __future__ import annotations

import json

from helpers.plugin import run_on
from helpers.traffic_dropin import CONFIG, copy_with_throwaway


def test_a_dropped_in_payload_runs_with_its_app(tmp_path):
    """One window, two UAVs, the echo payload emulated for real: the app's section in run.json."""
    pkg = copy_with_throwaway(tmp_path)
    out = tmp_path / "run"
    ran = run_on(pkg, "-m", "uavcas", "run", CONFIG, "--seed", "3", "--windows", "1", "--out", str(out),
               "--no-audit", timeout_s=300)
    assert ran.returncode == 0, ran.stderr[-2000:]
    info = json.loads((out / "run.json").read_text())
    assert info["http_clients"] == []  # no image app in this payload
    assert set(info["streams"]) == {"echo"}
    assert info["streams"]["echo"]["bs0"]["echoed"] > 0, info["streams"]
