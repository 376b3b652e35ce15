"""Real runs of the UAV traffic (issue 23): 6 UAVs, 2 BSs, 4 windows, payload `mixed` (MAVLink v2,
H.264 video and the image fetches at once) and payload `video` (MAVLink and video alone).

Checks, from the runs' logs and the BS switches' captures: every UAV the plan connects got its
mission uploaded and acknowledged and every window's speed command acknowledged; every
datagram to UDP 14550 at a BS's switch is a MAVLink 2 frame pymavlink parses with a valid CRC;
each GLOBAL_POSITION_INT, converted back to metres, is the plan's track at its time_boot_ms
within 1 m (and that time is the capture time within 0.5 s); `uavcas mavlink`'s table counts
each stream at its configured rate, and each UAV radio's RADIO_STATUS at 1 Hz with the plan's
values (rssi against the first hop's planned received power: r >= 0.9); the video reaches the BS
at its configured bitrate where the path's planned rate leaves room for it; both runs' fidelity
audits pass (the mixed run's as an expected failure while issue 28's saturated-link lateness is
open).
"""

from __future__ import annotations

from collections import Counter

import pytest

from helpers.audit_checks import assert_audit_passes
from uavcas.rundir import RunDir
from uavcas.testing.audited import run_audited
from uavcas.traffic.mavlink import read_log
from uavcas.twin.track import Track, geodetic_to_local

pytestmark = [pytest.mark.root, pytest.mark.slow]
CFG = "benign-6-2-{payload}-logdist-adaptive-random-30-95"
SEED = 14
VIDEO_KBPS = 400  # the `video` run's bitrate: 3 streams per BS leave the planned paths room
MIXED_VIDEO_KBPS = 200


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, RunDir]:
    # One run at a time: two emulations sharing the 2 cores, each with saturated links, push the
    # saturated hops' delay error past the audit's p99 tolerance (issue 28's weak spot), and the
    # audit must pass here. The mixed run's video at MIXED_VIDEO_KBPS keeps its queues from
    # staying full beside the image fetches.
    base = tmp_path_factory.mktemp("uavtraffic")
    extra = {"mixed": ["--video-kbps", str(MIXED_VIDEO_KBPS)], "video": ["--video-kbps", str(VIDEO_KBPS)]}
    for pl, args in extra.items():  # a try whose audit fails is made once more (`run_audited`)
        run_audited([CFG.format(payload=pl), "--seed", str(SEED), "--windows", "4", *args], base / pl, timeout_s=240)
    return {pl: RunDir(base / pl) for pl in extra}


@pytest.fixture(scope="module")
def run(runs) -> RunDir:
    return runs["mixed"]


# The mixed run's image fetches saturate several uplinks. While HTB paced them, a share of their
# crossings came one frame's serialisation time late after a host freeze (issue 28 item 3), and
# this test was an expected failure; the delay stage paces them since stop 27, and it passed in
# the last two fresh clones' suites.
def test_the_mixed_run_passes_its_audit(run):
    assert_audit_passes(run)


def test_missions_and_commands_are_acknowledged(run):
    plan, info = run.read_plan(), run.read_info()
    assert info.exit_status == 0 and len(info.http_clients) == 6  # mixed: the image fetches run too
    drops = {(r["window"], r["src"], r["dst"]): r["queue_drops"] or 0 for r in run.read_shaping()}

    def dropped_back(uav: str, bs: str, window: int) -> bool:
        """A hop of the UAV's planned path to the BS dropped frames at its queue tail in the window."""
        hops = next(r.hops for r in plan.windows[window].routes if (r.src, r.dst) == (uav, bs))
        return any(drops.get((window, a, b), 0) > 0 for a, b in zip(hops, hops[1:]))

    for bs in (n.name for n in plan.nodes if n.kind == "bs"):
        log = read_log(run.logs_dir / f"mavlink-{bs}.jsonl")
        served = next(e for e in log if e["event"] == "listening")["uavs"]
        assert served
        for uav in served:
            online = [w.index for w in plan.windows if uav not in plan.disconnected_uavs(w)]
            if not online:
                continue
            # Every exchange reaches the UAV, which accepts it. The BS hears the answer unless the
            # UAV's path back dropped frames at a full queue in that window: the image fetches
            # keep some uplinks saturated (uav4 -> bs0 tail-drops a quarter of its frames), and
            # four lost acks in a row there are the link's, not the application's.
            ulog = read_log(run.logs_dir / f"mavlink-{uav}.jsonl")
            assert [e["result"] for e in ulog if e["event"] == "mission_receive"] == ["accepted"]
            # the UAV's log has run time, not windows: a command is sent at its window's start
            answered = {int(e["t_s"] // plan.window_s) for e in ulog if e["event"] == "command" and e["result"] == 0}
            ups = [e for e in log if e["event"] == "mission_upload" and e["uav"] == uav]
            assert len(ups) == 1 and (ups[0]["result"] == "accepted" or dropped_back(uav, bs, 0)), (uav, ups)
            acks = {e["window"]: e["result"] for e in log if e["event"] == "command_result" and e["uav"] == uav}
            for k in (k for k in online if k >= 1):
                assert k in answered and (acks.get(k) == "accepted" or dropped_back(uav, bs, k)), (uav, k, acks)
            # run.json's streams summary says the same
            assert uav in info.streams["mavlink"][bs]["uploaded"]
            assert info.streams["mavlink"][bs]["received_by_uav"][uav]["GLOBAL_POSITION_INT"] > 0
    assert info.tool_versions["ffmpeg"] and info.versions["pymavlink"]
    assert set(info.streams["video"]) == {n.name for n in plan.nodes if n.kind == "bs"}
    assert all(v["rate_kbps"] > 0 for v in info.streams["video"].values()), info.streams["video"]


def test_positions_in_the_bs_captures_are_the_plans_track(run):
    from pymavlink.dialects.v20 import ardupilotmega as common  # the dialect both endpoints speak
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
            # the autopilot's frames carry its sysid; its radio's RADIO_STATUS SiK's '3' (radio.py)
            assert msg.get_srcSystem() == (51 if msg.get_type() == "RADIO_STATUS" else plan.node(uav).sysid)
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
    # every UAV's positions reach its BS (in a mixed run the shaped links also drop some in their
    # queues: what was sent is counted at the UAV's own switch, test_streams_at_their_configured_rates)
    online = {u for u in tracks if all(u not in plan.disconnected_uavs(w) for w in plan.windows)}
    assert online and all(positions[u] >= 10 for u in online), positions
    print(f"types {dict(types)}; worst position error {worst_m:.4f} m")


def test_streams_at_their_configured_rates_in_the_capture_table(run):
    from uavcas.mavlink_capture import mavlink_table, message_counts
    from uavcas.traffic.mavlink import StreamRates

    plan, t0 = run.read_plan(), run.read_info().t0_unix
    rates = StreamRates(stream_rate_hz=plan.mavlink_stream_hz)
    # every streamed message and HEARTBEAT (TERRAIN_REQUEST's 2 s minimum spacing on the stream's
    # ticks makes it 0.44-0.5 Hz: not a fixed rate to count)
    want = {k: v for k, v in rates.expected_hz().items() if k != "TERRAIN_REQUEST"}
    table = mavlink_table(run.root)
    assert table.crc_ok.fillna(False).all()  # every datagram on port 14550 parsed, CRC valid
    # whole seconds of the run, after the streams were requested and before the end
    first, last = int(t0) + 2, int(t0 + len(plan.windows) * plan.window_s) - 1
    for uav in (n for n in plan.nodes if n.kind == "uav"):
        # what the UAV's endpoint sent: counted where it enters the network, at its own switch
        sent = table[(table.src_ip == uav.ip) & (table.point == f"s-{uav.name}")]
        counts = message_counts(sent)
        for name, hz in want.items():
            seen = counts[counts.msg_name == name].set_index("second").messages
            # Every stream starts at once. A request lost on a loaded downlink is sent again by
            # MAVProxy's periodic request (`rerequest_s`, 15 s; a CI run once lost uav2's): its rate
            # counts from the whole second after its start.
            assert len(seen) and seen.index.min() < t0 + rates.rerequest_s + 2, (uav.name, name, seen.to_dict())
            per_s = seen.reindex(range(max(first, int(seen.index.min()) + 1), last), fill_value=0)
            assert abs(per_s.mean() - hz) <= 0.1 * hz, (uav.name, name, per_s.tolist())


def test_each_uavs_radio_reports_its_planned_link_at_1_hz(run):
    # issue 39 item 2: at each UAV's own switch (every report it sent, once), RADIO_STATUS under
    # SiK's ids once a second, each the plan's values, and its rssi following the first hop's
    # planned received power across windows
    import json

    import numpy as np

    from uavcas.mavlink_capture import mavlink_table
    from uavcas.traffic.mavlink import radio, radio_spec

    plan, t0 = run.read_plan(), run.read_info().t0_unix
    table = mavlink_table(run.root)
    reports = table[(table.msg_name == "RADIO_STATUS") & table.crc_ok.fillna(False).astype(bool)]
    per = round(plan.window_s / radio.REPORT_PERIOD_S)
    budget, rssi = [], []
    for uav in (n for n in plan.nodes if n.kind == "uav"):
        sent = reports[(reports.src_ip == uav.ip) & (reports.point == f"s-{uav.name}")].sort_values("ts_ns")
        assert set(zip(sent.sysid.astype(int), sent.compid.astype(int))) == {(51, 68)}, uav.name
        in_plan = sent[sent.ts_s < t0 + plan.duration_s]
        assert abs(len(in_plan) - plan.duration_s / radio.REPORT_PERIOD_S) <= 1, (uav.name, len(in_plan))
        gaps = np.diff(sent.ts_s.to_numpy())
        assert ((gaps > 0.8) & (gaps < 1.2)).all(), (uav.name, gaps)
        want = radio_spec(plan, uav.name).reports
        got = [json.loads(f) for f in in_plan.fields_json]
        keys = ("rssi", "remrssi", "txbuf", "noise", "remnoise", "rxerrors", "fixed")
        assert [tuple(g[k] for k in keys) for g in got] == [tuple(getattr(w, k) for k in keys)
                                                            for w in want[:len(got)]], uav.name
        for hop in radio.first_hop_budgets(plan, uav.name):
            if hop.rx_dbm is not None:
                budget.append(hop.rx_dbm)
                rssi.append(np.mean([g["rssi"] for g in got[hop.window * per:(hop.window + 1) * per]]))
    r = float(np.corrcoef(budget, rssi)[0, 1])
    print(f"RADIO_STATUS: {len(budget)} UAV-windows, r(first-hop P_rx, mean rssi) = {r:.3f}")
    assert r >= 0.9, r


def test_video_reaches_the_bs_at_its_bitrate_where_the_path_has_room(runs):
    import numpy as np

    from uavcas.flows.packets import addresses_to_str, read_packets
    from uavcas.traffic.image.client import assignments

    run = runs["video"]
    plan, info = run.read_plan(), run.read_info()
    assert_audit_passes(run)
    pcaps = run.pcaps()
    p = read_packets(pcaps, points=[x.stem for x in pcaps])
    src = addresses_to_str(p["src_hi"], p["src_lo"])
    point = np.asarray(p.points)[p["point"]]
    rtp = (p["proto"] == 17) & (p["dport"] == 5600)
    # what the sender's encoder puts on the wire: RTP header and H.264, above UDP
    payload = p["ip_len"].astype(np.int64) - p["ip_hdr_len"] - 8
    pairs = assignments([n.name for n in plan.nodes if n.kind == "uav"], [n.name for n in plan.nodes if n.kind == "bs"])
    per_bs = {bs: sum(1 for b, _ in pairs if b == bs) for bs, _ in pairs}
    duration_s = len(plan.windows) * plan.window_s
    checked = 0
    for bs, uav in pairs:
        # the path's planned bottleneck, every window: room for every stream to that BS twice over
        room = True
        for w in plan.windows:
            route = next((r for r in w.routes if r.src == uav and r.dst == bs), None)
            links = {frozenset((lk.a, lk.b)): lk.rate_mbps for lk in w.links}
            if route is None or min(links[frozenset(h)] for h in zip(route.hops, route.hops[1:])) * 1000 \
                    < 2 * per_bs[bs] * VIDEO_KBPS:
                room = False
        if not room:
            continue
        m = rtp & (src == plan.node(uav).ip) & (point == f"s-{bs}")
        t = p["ts_s"][m] - info.t0_unix
        steady = (t >= 2.0) & (t < duration_s - 1.0)  # after ffmpeg's start, before the end
        kbps = payload[m][steady].sum() * 8 / 1000 / (duration_s - 3.0)
        assert abs(kbps - VIDEO_KBPS) <= 0.1 * VIDEO_KBPS, (uav, bs, kbps)
        checked += 1
    assert checked >= 3
