"""The UAV radio's RADIO_STATUS values (traffic/mavlink/radio.py), pure: from a real plan."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega, common

from uavcas.mavlink_capture import decode_datagrams
from uavcas.traffic.mavlink import radio as R
from uavcas.traffic.mavlink import specs
from uavcas.twin.plan import plan
from uavcas.twin.profile import load_profile

CFG = "benign-5-2-mixed-logdist-adaptive-random-30-95"  # the quick preset's benign scenario
CFG_10DBM = "blackhole+dos=1000-6-2-mixed-3gpp-adaptive-random-10-95"  # quick preset: has disconnected windows


@pytest.fixture(scope="module")
def p():
    return plan(CFG, seed=0, windows=12)


def _uavs(pl):
    return [n.name for n in pl.nodes if n.kind == "uav"]


def test_sik_scale_round_trips_and_clips_to_uint8():
    # dBm = units / 1.9 - 127 (QGroundControl's conversion of a '3'/'D' report)
    assert R.dbm_to_units(-127.0) == 0 and R.dbm_to_units(-60.0) == round(67 * 1.9)
    assert R.dbm_to_units(-140.0) == 0 and R.dbm_to_units(10.0) == 255
    for dbm in np.linspace(-126.0, 7.0, 50):
        assert abs(R.units_to_dbm(R.dbm_to_units(dbm)) - dbm) <= 0.5 / 1.9 + 1e-9


def test_first_hop_budget_is_the_channels_received_power(p):
    # P_rx = P_tx + G_tx + G_rx - pathloss_db (shadowing inside): the plan's own numbers
    ch = load_profile(p.profile).channel
    for uav in _uavs(p):
        for hop in R.first_hop_budgets(p, uav):
            w = p.windows[hop.window]
            route = next(r for r in w.routes if r.src == uav and r.dst.startswith("bs"))
            assert hop.peer == route.hops[1]
            link = next(lk for lk in w.links if {lk.a, lk.b} == {uav, hop.peer})
            want = p.scenario.tx_dbm + ch.tx_gain_dbi + ch.rx_gain_dbi - link.pathloss_db
            assert hop.rx_dbm == pytest.approx(want, abs=0.01)  # the plan rounds to 1e-3 dB
            assert hop.loss == link.loss and hop.rate_mbps == link.rate_mbps


def test_rssi_follows_the_first_hop_budget_across_windows(p):
    # the reviewer's check: per window, the mean reported rssi against the planned first-hop
    # received power, over every UAV and window of the plan
    budget, rssi = [], []
    per = round(p.window_s / R.REPORT_PERIOD_S)
    for uav in _uavs(p):
        reports = specs.radio_spec(p, uav).reports
        assert len(reports) == round(p.duration_s / R.REPORT_PERIOD_S)
        assert [r.t_s for r in reports] == [k * R.REPORT_PERIOD_S for k in range(len(reports))]
        for hop in R.first_hop_budgets(p, uav):
            if hop.rx_dbm is not None:
                budget.append(hop.rx_dbm)
                rssi.append(np.mean([r.rssi for r in reports[hop.window * per:(hop.window + 1) * per]]))
    assert len(budget) >= 50
    r = float(np.corrcoef(budget, rssi)[0, 1])
    assert r >= 0.9, r
    # and on the scale: the mean report is the budget in SiK units, fading averaging out (E g = 1
    # in linear power: its mean in dB lies a little below 0)
    offset_db = np.mean([R.units_to_dbm(u) - b for u, b in zip(rssi, budget)])
    assert -3.0 < offset_db < 0.5, offset_db


def test_reports_are_reproducible_and_seeded(p):
    a, b = specs.radio_spec(p, "uav0"), specs.radio_spec(p, "uav0")
    assert a == b
    other = specs.radio_spec(plan(CFG, seed=1, windows=12), "uav0")
    assert [r.rssi for r in other.reports] != [r.rssi for r in a.reports]
    assert [r.rssi for r in specs.radio_spec(p, "uav1").reports] != [r.rssi for r in a.reports]


def test_noise_counters_and_txbuf_of_a_connected_uav(p):
    noise = R.dbm_to_units(p.scenario.noise_dbm)
    for uav in _uavs(p):
        reports = specs.radio_spec(p, uav).reports
        assert all(r.noise == noise and r.remnoise == noise for r in reports)  # no jammer in this plan
        assert all(r.fixed == 0 for r in reports)  # SiK's default ECC 0: nothing corrected
        errs = [r.rxerrors for r in reports]
        assert errs == sorted(errs)  # a counter: it only grows
        assert all(r.txbuf == 100 for r in reports)  # kB/s of telemetry on a Mb/s link: idle


def test_a_disconnected_uav_reports_no_remote():
    pl = plan(CFG_10DBM, seed=0, windows=12)
    noise = R.dbm_to_units(pl.scenario.noise_dbm)
    seen = 0
    for uav in _uavs(pl):
        reports = specs.radio_spec(pl, uav).reports
        for w in pl.windows:
            if uav not in pl.disconnected_uavs(w):
                continue
            k0 = round(w.t_s / R.REPORT_PERIOD_S)
            for r in reports[k0:k0 + round(pl.window_s / R.REPORT_PERIOD_S)]:
                seen += 1
                assert (r.rssi, r.remrssi, r.remnoise, r.noise, r.txbuf) == (noise, 0, 0, noise, 100)
    assert seen > 0


def test_rxerrors_accumulate_from_the_planned_loss_and_saturate():
    pl = plan(CFG_10DBM, seed=0, windows=12)
    uav = "uav0"
    offered, frame = R.mavlink_load(specs.StreamRates().expected_hz())
    hops = R.first_hop_budgets(pl, uav)
    few = R.radio_reports(pl, uav, offered, frame, rx_frames_per_s=1000.0)
    per = round(pl.window_s)
    # errors per connected window ~ frames x loss: the binomial mean within 5 sd (+1)
    for hop in hops:
        if hop.peer is None or hop.window == 0:
            continue
        k = hop.window * per
        got = few[k + per - 1].rxerrors - few[k - 1].rxerrors
        n = 1000 * per
        assert abs(got - n * hop.loss) <= 5 * math.sqrt(n * hop.loss * (1 - hop.loss)) + 1, (hop, got)
    many = R.radio_reports(pl, uav, offered, frame, rx_frames_per_s=1e7)
    assert many[-1].rxerrors == R.COUNTER_MAX  # saturates, as SiK's uint16 counters do


def test_txbuf_is_sik_serial_read_space_of_the_queue():
    assert R.txbuf_percent(0.0, 1.0, 45.0) == 100
    assert R.txbuf_percent(2e6, 1.0, 45.0) == 0  # offered beyond the link: the buffer is full
    pct = [R.txbuf_percent(f * 1e6, 1.0, 200.0) for f in (0.1, 0.5, 0.8, 0.9, 0.99)]
    assert pct == sorted(pct, reverse=True) and pct[-1] == 0
    # rho 0.1: 0.111 frames of 200 B = 23 B used; serial.c: 100 * ((1850 - 23) // 8) // (1850 // 8)
    assert pct[0] == 100 * ((1850 - 23) // 8) // (1850 // 8) == 98


def test_radio_status_on_the_wire_is_sik_shaped(p):
    report = specs.radio_spec(p, "uav0").reports[3]
    mav = common.MAVLink(None, srcSystem=R.SIK_SYSID, srcComponent=R.SIK_COMPID)
    frame = R.message(report).pack(mav)
    assert frame[0] == 0xFD and frame[7:10] == bytes([109, 0, 0])  # MAVLink 2, id 109 (mavlink.c)
    assert len(frame) == 9 + 12  # SiK's struct mavlink_RADIO_v10 (9 bytes) + 12: nothing truncated
    (msg,) = ardupilotmega.MAVLink(None).parse_buffer(frame)  # what `uavcas mavlink` decodes with
    assert (msg.get_type(), msg.get_srcSystem(), msg.get_srcComponent()) == ("RADIO_STATUS", 51, 68)
    assert (msg.rssi, msg.remrssi, msg.txbuf, msg.noise, msg.remnoise, msg.rxerrors, msg.fixed) == (
        report.rssi, report.remrssi, report.txbuf, report.noise, report.remnoise, report.rxerrors, report.fixed)
    # `uavcas mavlink`'s decoder gives it a good row with its fields
    (row,) = decode_datagrams([frame]).to_dict("records")
    assert (row["msg_name"], row["msg_id"], row["crc_ok"], row["sysid"], row["compid"]) == (
        "RADIO_STATUS", 109, True, 51, 68)
    assert json.loads(row["fields_json"])["rssi"] == report.rssi


def test_a_jammer_raises_the_noise_each_end_reads_while_it_is_on():
    # SiK samples noise with the RSSI register: a jammer's power at that end adds to the floor
    pl = plan("jamming=20-5-2-mixed-logdist-adaptive-random-30-95", seed=0, windows=12)
    floor_dbm = pl.scenario.noise_dbm
    jammed = 0
    for uav in _uavs(pl):
        reports = specs.radio_spec(pl, uav).reports
        for hop in R.first_hop_budgets(pl, uav):
            if hop.peer is None:
                continue
            w = pl.windows[hop.window]
            for r in reports[round(w.t_s):round(w.t_s + pl.window_s)]:
                at = {(o.src, o.dst): o for o in w.link_overrides if o.start_s <= r.t_s < o.stop_s}
                for (src, dst), field in (((hop.peer, uav), "noise"), ((uav, hop.peer), "remnoise")):
                    o = at.get((src, dst))
                    want = floor_dbm if o is None else 10 * math.log10(10 ** (floor_dbm / 10)
                                                                       + 10 ** (o.interference_dbm / 10))
                    assert getattr(r, field) == R.dbm_to_units(want), (uav, r, field)
                    jammed += o is not None and getattr(r, field) > R.dbm_to_units(floor_dbm)
    assert jammed > 0


def test_the_fading_is_the_plans_profiles_or_none(p):
    assert R.plan_fading(p) == load_profile(p.profile).channel.fading
    # a plan whose recorded profile is not the one its name now finds: no fading, not another's
    other = p.model_copy(update={"profile_sha256": "0" * 64})
    assert R.plan_fading(other) is None
    flat = R.radio_reports(other, "uav0", 0.0, 0.0, 1.0)
    per = round(p.window_s)
    for hop in R.first_hop_budgets(other, "uav0"):
        assert hop.k_db is None
        assert {r.rssi for r in flat[hop.window * per:(hop.window + 1) * per]} == {R.dbm_to_units(hop.rx_dbm)}
