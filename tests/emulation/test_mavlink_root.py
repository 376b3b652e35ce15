"""A real `telemetry` run: 6 UAVs, 2 BSs, 4 windows of MAVLink v2 and nothing else (issue 23).

Checks, from the run's logs and the BS switches' captures: every UAV the plan connects got its
mission uploaded and acknowledged and every window's speed command acknowledged; every
datagram to UDP 14550 at a BS's switch is a MAVLink 2 frame pymavlink parses with a valid CRC;
each GLOBAL_POSITION_INT, converted back to metres, is the plan's track at its time_boot_ms
within 1 m (and that time is the capture time within 0.5 s); the run's fidelity audit passes.
"""

from __future__ import annotations

import subprocess
import sys
from collections import Counter

import pytest

from uavcas.emulation.apps.mavlink import read_log
from uavcas.rundir import RunDir
from uavcas.twin.track import Track, geodetic_to_local

pytestmark = [pytest.mark.root, pytest.mark.slow]
CFG = "benign-6-2-telemetry-logdist-adaptive-random-30-95"
SEED = 14


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("mavlink") / "run"
    r = subprocess.run([sys.executable, "-m", "uavcas.cli", "run", CFG, "--seed", str(SEED), "--windows", "4",
                        "--out", str(out)], capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, (r.stdout + r.stderr)[-2000:]
    return RunDir(out)


def test_missions_and_commands_are_acknowledged_and_no_http_runs(run):
    plan, info = run.read_plan(), run.read_info()
    assert info.exit_status == 0 and info.http_clients == []  # telemetry: MAVLink alone
    assert info.fidelity is not None and info.fidelity.verdict == "pass", info.fidelity
    for bs in (n.name for n in plan.nodes if n.kind == "bs"):
        log = read_log(run.logs_dir / f"mavlink-{bs}.jsonl")
        served = next(e for e in log if e["event"] == "listening")["uavs"]
        assert served
        for uav in served:
            online = [w.index for w in plan.windows if uav not in plan.disconnected_uavs(w)]
            if not online:
                continue
            ups = [e for e in log if e["event"] == "mission_upload" and e["uav"] == uav]
            assert [e["result"] for e in ups] == ["accepted"], (uav, ups)
            acks = {e["window"]: e["result"] for e in log if e["event"] == "command_result" and e["uav"] == uav}
            assert all(acks.get(k) == "accepted" for k in online if k >= 1), (uav, acks)
            ulog = read_log(run.logs_dir / f"mavlink-{uav}.jsonl")
            assert [e["result"] for e in ulog if e["event"] == "mission_receive"] == ["accepted"]


def test_positions_in_the_bs_captures_are_the_plans_track(run):
    from pymavlink.dialects.v20 import common
    from scapy.layers.inet import IP, UDP
    from scapy.utils import rdpcap

    plan, t0 = run.read_plan(), run.read_info().t0_unix
    ip_of = {n.ip: n.name for n in plan.nodes}
    tracks = {n.name: Track.of(plan, n.name) for n in plan.nodes if n.kind == "uav"}
    types, positions, worst_m = Counter(), Counter(), 0.0
    for bs in (n.name for n in plan.nodes if n.kind == "bs"):
        for pkt in rdpcap(str(run.pcap_dir / f"s-{bs}.pcap")):
            if UDP not in pkt or pkt[UDP].dport != 14550 or pkt[IP].dst != plan.node(bs).ip:
                continue
            mav = common.MAVLink(None)  # strict parser: a bad CRC raises
            (msg,) = mav.parse_buffer(bytes(pkt[UDP].payload))
            uav = ip_of[pkt[IP].src]
            assert msg.get_srcSystem() == plan.node(uav).sysid
            types[msg.get_type()] += 1
            if msg.get_type() == "GLOBAL_POSITION_INT":
                positions[uav] += 1
                x, y, z = geodetic_to_local(plan.site, msg.lat / 1e7, msg.lon / 1e7, msg.alt / 1000)
                q = tracks[uav].at(msg.time_boot_ms / 1000)
                err = max(abs(x - q.x_m), abs(y - q.y_m), abs(z - q.z_m))
                worst_m = max(worst_m, err)
                assert err < 1.0, (uav, msg, q)
                assert abs(float(pkt.time) - t0 - msg.time_boot_ms / 1000) < 0.5
    assert set(types) >= {"HEARTBEAT", "SYS_STATUS", "GPS_RAW_INT", "GLOBAL_POSITION_INT", "ATTITUDE", "VFR_HUD",
                          "MISSION_REQUEST_INT", "MISSION_ACK", "COMMAND_ACK"}
    # 4 Hz over ~20 s for every UAV the plan keeps connected
    online = {u for u in tracks if all(u not in plan.disconnected_uavs(w) for w in plan.windows)}
    assert online and all(positions[u] >= 60 for u in online), positions
    print(f"types {dict(types)}; worst position error {worst_m:.4f} m")
