"""A traffic app is added by dropping one module into `uavcas.traffic.apps`, and a payload by one
row of `uavcas.traffic.payloads.PAYLOADS` (issue 40).

A copy of the package gets a throwaway app, `echo`: a TCP echo server on every base station and
a client per UAV that sends a block to its BS and reads it back, over and over; and a payload
`echo` whose row names it. In a fresh interpreter that imports only the copy, the registry offers
the app, the scenario codec accepts the payload (and still refuses one the table lacks, in one
line), `uavcas plan` plans it, and `uavcas run --mavlink-signing` refuses it for carrying no
MAVLink, before any root check. The real run of the payload (root) checks that its run.json
carries the app's own section, with blocks echoed on every BS.
"""

from __future__ import annotations

import json

import pytest

from helpers.plugin import run_on
from helpers.traffic_dropin import CONFIG, copy_with_throwaway


@pytest.mark.slow  # 17 s on 2 cores
def test_a_dropped_in_app_and_payload_row_are_registered_parsed_and_planned(tmp_path):
    pkg = copy_with_throwaway(tmp_path)
    probe = run_on(pkg, "-c", "import uavcas, uavcas.traffic.apps as a; from uavcas.scenario import parse; "
                            "print(uavcas.__file__); print(' '.join(a.names())); print(' '.join(a.MAVLINK_PAYLOADS)); "
                            "print([c.__name__ for c in a.payload_apps('echo')]); "
                            f"print(parse({CONFIG!r}).payload)")
    assert probe.returncode == 0, probe.stderr
    where, names, mavlink, classes, payload = probe.stdout.splitlines()
    assert where.startswith(str(pkg))
    assert names.split() == ["echo", "image", "mavlink", "video"]  # module order
    assert mavlink.split() == ["telemetry", "video", "mixed"]  # echo carries no MAVLink
    assert classes == "['EchoApp']" and payload == "echo"

    refused = run_on(pkg, "-m", "uavcas", "plan", CONFIG.replace("echo", "ping"))
    assert refused.returncode != 0
    assert "field 'payload': 'ping' is not one of image, telemetry, video, mixed, echo" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1, refused.stderr

    out = tmp_path / "plan.json"
    planned = run_on(pkg, "-m", "uavcas", "plan", CONFIG, "--seed", "3", "--windows", "1", "--out", str(out))
    assert planned.returncode == 0, planned.stderr
    plan = json.loads(out.read_text())
    assert plan["config"] == CONFIG and plan["scenario"]["payload"] == "echo"
    assert sum(n["kind"] == "uav" for n in plan["nodes"]) == 2 and len(plan["windows"]) == 1

    signed = run_on(pkg, "-m", "uavcas", "run", CONFIG, "--out", str(tmp_path / "run"), "--mavlink-signing")
    assert signed.returncode != 0 and "payload 'echo' carries no MAVLink" in signed.stderr
    assert not (tmp_path / "run").exists()
