"""The audit on synthetic runs whose emulator errors and losses are known (fidsynth)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from helpers.fidsynth import T0, Traffic, build, plan, run_info
from uavcas.fidelity import Tolerances, audit, audit_run, read_fidelity, write_fidelity
from uavcas.fidelity.model import SCHEMA_VERSION
from uavcas.network.queues import queue_limit_pkts
from uavcas.rundir import RunDir, WindowApply


def _steady(n=400, gap_s=0.004, t0=0.1, length=600, sport=5000) -> Traffic:
    tr = Traffic()
    for k in range(n):
        tr.add(t0 + k * gap_s, length, sport)
    return tr


def test_a_perfect_emulator_passes_with_zero_error(tmp_path):
    tr = _steady()
    for k in range(40):  # a burst well over the rate: the model queues it
        tr.add(3.0, 1000, 6000)
    f = audit(build(tmp_path, plan(), tr).root)
    assert f.verdict == "pass" and f.failed == []
    assert f.n == 2 * 440 and f.packets == 440 and f.crossings_unmodelled == 0
    for q in (f.delay_error_p1_ms, f.delay_error_p50_ms, f.delay_error_p99_ms, f.delay_error_max_ms):
        assert abs(q) < 0.002  # pcap stamps are microseconds
    assert f.saturated_bins == 0  # 40 kB at 1 B/us: 40 ms of queue, no whole 200 ms bin
    lw = {(x.src, x.dst, x.window): x for x in f.links}
    assert set(lw) == {("uav0", "uav1", 0), ("uav1", "bs0", 0)}
    first = lw[("uav0", "uav1", 0)]
    assert first.n == 440 and first.planned_delay_ms == 2.0 and first.lost == 0
    # the queued burst shows in the model's delay, not in the error
    assert first.model_delay_p50_ms == pytest.approx(first.measured_delay_p50_ms, abs=0.002)


def test_saturated_link_throughput_is_measured_against_the_plan(tmp_path):
    tr = Traffic()
    for k in range(700):  # 700 kB offered at once on 1 B/us: 0.7 s of backlog
        tr.add(0.5, 1000, 6000)
    f = audit(build(tmp_path, plan(), tr).root)
    assert f.saturated_bins >= 2 and f.throughput_ratio_p50 == pytest.approx(1.0, abs=0.01)
    assert [c.ok for c in f.checks if c.name == "throughput_rel"] == [True]


def test_a_slow_saturated_link_at_its_planned_rate_reads_a_ratio_of_one(tmp_path):
    # 0.27 Mbit/s: a 1514-byte frame takes 44.9 ms, a 200 ms bin holds 4 or 5 whole ones (0.91 or
    # 1.14 of the rate counted whole); spread over their serialisation times they fill it exactly.
    # A frame every 40 ms offers 1.12 times the rate: the queue never empties, never overflows.
    tr = Traffic()
    for k in range(110):
        tr.add(0.1 + 0.04 * k, 1514, 6000)
    f = audit(build(tmp_path, plan(rate_mbps=0.27), tr).root)
    assert f.saturated_bins >= 15 and f.throughput_ratio_p50 == pytest.approx(1.0, abs=0.02)
    assert f.delay_error_max_ms < 0.002 and f.lost == 0 and f.verdict == "pass"
    # an emulator that held the link at 90 % of the planned rate reads 0.9 and fails the check
    rd = build(tmp_path / "slow", plan(rate_mbps=0.27 * 0.9), tr)
    rd.plan_json.write_text(plan(rate_mbps=0.27).to_json())
    slow = audit(rd.root)
    assert slow.throughput_ratio_p50 == pytest.approx(0.9, abs=0.02) and "throughput_rel" in slow.failed


def test_late_releases_show_as_delay_error_and_fail_a_tight_tolerance(tmp_path):
    rng = np.random.default_rng(3)
    late = {(h, k): (3e-4 if rng.random() < 0.05 else 5e-5) for h in range(2) for k in range(400)}
    rd = build(tmp_path, plan(), _steady(), error=lambda h, k: late[(h, k)])
    f = audit(rd.root)
    assert f.delay_error_p50_ms == pytest.approx(0.05, abs=0.002)
    assert f.delay_error_p99_ms == pytest.approx(0.3, abs=0.002)
    assert f.verdict == "pass"  # within the 20-UAV defaults: p90 0.2, p99 0.5
    tight = audit(rd.root, Tolerances(delay_error_p99_ms=0.25))
    assert tight.verdict == "fail" and tight.failed == ["delay_error_p99_ms"]
    assert tight.late_over_1ms == 0.0


def test_random_loss_is_held_to_the_planned_loss(tmp_path):
    lossy = plan(loss_b=0.1)
    ok = audit(build(tmp_path / "ok", lossy, _steady(), drop=lambda h, k: h == 1 and k % 10 == 3).root)
    assert ok.loss_random_observed == 40 and ok.loss_random_expected == pytest.approx(40.0)
    assert abs(ok.loss_sigma) < 0.5 and ok.verdict == "pass"
    hop = next(x for x in ok.links if x.src == "uav1")
    assert hop.lost == 40 and hop.lost_tail == 0 and hop.loss_random == pytest.approx(0.1)
    bad = audit(build(tmp_path / "bad", lossy, _steady(), drop=lambda h, k: h == 1 and k % 10 < 3).root)
    assert bad.loss_random_observed == 120 and bad.loss_sigma > 10 and "loss_sigma" in bad.failed
    lossless = audit(build(tmp_path / "none", plan(), _steady(), drop=lambda h, k: h == 0 and k in (7, 9)).root)
    assert lossless.loss_random_observed == 2 and lossless.verdict == "pass"  # a lossless plan tolerates a few


def test_queue_tail_drops_are_told_from_random_loss(tmp_path):
    # 100 frames at once on 8 Mbit/s: two leave at once (the bucket), `limit` wait in the queue
    # and the emulator drops the rest at its tail
    limit = queue_limit_pkts(8.0)
    tr = Traffic()
    for k in range(100):
        tr.add(1.0, 1000, 6000)
    f = audit(build(tmp_path, plan(), tr, drop=lambda h, k: h == 0 and k >= limit + 2).root)
    assert f.lost == 98 - limit and f.lost_tail == f.lost and f.loss_random_observed == 0 and f.verdict == "pass"
    # the same losses from a queue the model says was half empty are random ones
    rd = build(tmp_path / "r", plan(), tr, drop=lambda h, k: h == 0 and k >= limit // 2)
    g = audit(rd.root)
    assert g.lost_tail == 0 and g.loss_random_observed == g.lost and g.failed == ["loss_sigma"]
    # ... unless the kernel counted them as tail drops of that port in that window
    rec = {"window": 0, "src": "uav0", "dst": "uav1", "port": "l0-1", "backend": "htb-nft-nfqueue",
           "planned_rate_mbps": 8.0, "planned_delay_ms": 2.0, "planned_loss": 0.0, "applied_rate_mbps": 8.0,
           "applied_delay_ms": 2.0, "applied_loss": 0.0, "sent_packets": 100 - g.lost, "queue_drops": g.lost,
           "loss_drops": 0, "link_drops": 0}
    rd.shaping_jsonl.write_text(json.dumps(rec) + "\n")
    h = audit(rd.root)
    assert h.lost_tail == g.lost and h.loss_random_observed == 0 and h.verdict == "pass"
    assert next(lw for lw in h.links if lw.src == "uav0").counters.queue_drops == g.lost


def test_random_drops_at_a_full_queue_are_random_when_the_kernel_counted_them(tmp_path):
    # uav0 -> uav1 plans 10 % loss. A burst fills the queue (two leave at once, `limit` wait), then
    # a frame every 0.9 ms, 1/0.9 of the rate: the loss rule drops every tenth, which is exactly
    # what keeps the queue at its limit without a tail drop. The model finds each lost frame at a
    # full queue, so on its own it calls them all tail drops and the random loss far too low.
    limit = queue_limit_pkts(8.0)
    tr = Traffic()
    for k in range(limit + 1):
        tr.add(1.0, 1000, 6000)
    for k in range(1000):
        tr.add(1.0 + 0.0009 * (k + 1), 1000, 5000)
    rd = build(tmp_path, plan(loss_a=0.1), tr, drop=lambda h, k: h == 0 and k > limit and (k - limit) % 10 == 0)
    g = audit(rd.root)
    assert g.lost == 100 and g.lost_tail == 100 and g.lost_random == 0
    assert g.loss_sigma < -8 and g.failed == ["loss_sigma"]
    hop = next(lw for lw in g.links if lw.src == "uav0")
    assert (hop.loss_source, hop.loss_offered, hop.loss_drops) == ("model", 935, 0)
    # the port's counters: no pfifo drop, 100 loss-rule drops out of 1035 frames offered
    rec = {"window": 0, "src": "uav0", "dst": "uav1", "sent_packets": 935, "queue_drops": 0, "loss_drops": 100,
           "link_drops": 0}
    rd.shaping_jsonl.write_text(json.dumps(rec) + "\n")
    f = audit(rd.root)
    assert f.verdict == "pass" and f.lost_tail == 0 and f.lost_random == 100 and f.lost_unexplained == 0
    assert f.loss_random_observed == 100 and f.loss_random_expected == pytest.approx(103.5)
    assert f.loss_sigma == pytest.approx((100 - 103.5) / np.sqrt(1035 * 0.1 * 0.9), abs=1e-3)
    assert f.loss_links_counted == 1 and f.queue_over_limit == 0
    hop = next(lw for lw in f.links if lw.src == "uav0")
    assert (hop.loss_source, hop.loss_offered, hop.loss_drops, hop.lost_random) == ("counters", 1035, 100, 100)


def test_losses_at_a_window_change_are_counted_apart(tmp_path):
    tr = _steady(n=100, t0=4.8)  # 4.8 .. 5.2 s: across the change at 5 s
    f = audit(build(tmp_path, plan(), tr, drop=lambda h, k: h == 1 and k in (45, 50, 55)).root)
    assert f.lost == 3 and f.lost_transition == 3 and f.loss_random_observed == 0


def test_gap_distortion_end_to_end(tmp_path):
    tr = _steady(n=200, gap_s=0.01)
    # every other packet 3 ms late on its last hop: gaps of 10 ms become 13 / 7 ms
    f = audit(build(tmp_path, plan(), tr, error=lambda h, k: 0.003 if h == 1 and k % 2 else 0.0).root)
    assert f.gaps.gaps == 199 and f.gaps.gap_p50_ms == pytest.approx(10.0, abs=0.01)
    assert f.gaps.shift_p50_ms == pytest.approx(3.0, abs=0.01) and f.gaps.shift_over_half_gap == 0.0
    worse = audit(build(tmp_path / "w", plan(), tr, error=lambda h, k: 0.006 if h == 1 and k % 2 else 0.0).root)
    assert worse.gaps.shift_over_half_gap == 1.0


def test_schedule_checks_come_from_run_json(tmp_path):
    slow = WindowApply(window=1, t_unix=T0 + 5, links_up=0, links_down=0, fdb_changes=0, rejected=[],
                       timings_s={"total_s": 0.4})
    rd = build(tmp_path, plan(), _steady(n=50), info=run_info(window_applies=[slow]))
    f = audit(rd.root)
    assert f.window_change_max_ms == pytest.approx(400.0) and f.failed == ["window_change_ms"]
    tight = WindowApply(**{**slow.model_dump(), "timings_s": {"total_s": 0.101}})  # just over 100 ms: fails
    assert audit(build(tmp_path / "t", plan(), _steady(n=50), info=run_info(window_applies=[tight])).root).failed == [
        "window_change_ms"]


def test_write_fidelity_writes_the_file_and_the_run_json_summary(tmp_path):
    rd = build(tmp_path, plan(), _steady(n=80))
    f = write_fidelity(rd.root)
    on_disk = json.loads(rd.fidelity_json.read_text())
    for key in ("verdict", "delay_error_p50_ms", "delay_error_p90_ms", "delay_error_p99_ms"):
        assert key in on_disk and key in on_disk["links"][0]
    assert read_fidelity(rd.root) == f
    s = RunDir(rd.root).read_info().fidelity
    assert s.verdict == f.verdict == "pass" and s.delay_error_p99_ms == f.delay_error_p99_ms
    assert read_fidelity(tmp_path / "nowhere") is None


def test_audit_run_writes_the_audit_or_records_why_it_could_not(tmp_path):
    rd = build(tmp_path / "ok", plan(), _steady(n=80))
    info = audit_run(rd.root)
    assert info == RunDir(rd.root).read_info() and info.fidelity.verdict == read_fidelity(rd.root).verdict == "pass"
    broken = build(tmp_path / "broken", plan(), _steady(n=80))
    broken.forwarding_jsonl.write_text("not a record\n")
    info = audit_run(broken.root)  # the audit fails; the run stays, with the error in run.json
    assert info.fidelity.verdict == "error" and "forwarding.jsonl:1" in info.fidelity.error
    assert not broken.fidelity_json.exists() and info.exit_status == 0


def test_one_set_of_tolerances_for_every_swarm_size(tmp_path):
    """A 100-UAV plan is held to the same limits as a 20-UAV one (p99 0.5 ms)."""
    p = plan()
    more = [p.nodes[0].model_copy(update={"name": f"uav{k}", "index": k + 1, "ip": f"10.20.2.{k}",
                                          "mac": f"02:00:00:00:02:{k:02x}"}) for k in range(2, 100)]
    big = p.model_copy(update={"nodes": p.nodes + more})
    assert sum(n.kind == "uav" for n in big.nodes) == 100
    late = build(tmp_path, big, _steady(), error=lambda h, k: 0.0008 if k % 20 == 0 else 0.0)
    f = audit(late.root)
    assert f.tolerances == Tolerances() and f.tolerances.delay_error_p99_ms == 0.5
    assert f.delay_error_p99_ms == pytest.approx(0.8, abs=0.002) and f.failed == ["delay_error_p99_ms"]


def test_audit_cli_re_audits_a_run_in_place(tmp_path):
    from typer.testing import CliRunner

    from uavcas.cli import app

    lossy = plan(loss_b=0.1)
    rd = build(tmp_path, lossy, _steady(), drop=lambda h, k: h == 1 and k % 10 < 3)
    stale = write_fidelity(rd.root).model_copy(update={"schema_version": 1, "verdict": "pass", "failed": []})
    rd.fidelity_json.write_text(stale.to_json())
    r = CliRunner().invoke(app, ["audit", str(rd.root), "--links", "2"])
    assert r.exit_code == 1, r.output  # the 30 % loss against 10 % planned fails, as before the stale file
    f = read_fidelity(rd.root)
    assert f.schema_version == SCHEMA_VERSION and f.failed == ["loss_sigma"] and f.lost_random == 120
    assert RunDir(rd.root).read_info().fidelity.failed == ["loss_sigma"]
    assert sorted(p.name for p in rd.root.iterdir() if p.is_file()) == ["fidelity.json", "forwarding.jsonl",
                                                                        "plan.json", "run.json"]
    r = CliRunner().invoke(app, ["audit", str(rd.root), "--loss-sigma", "100"])
    assert r.exit_code == 0 and read_fidelity(rd.root).verdict == "pass"


def test_a_mid_window_reshape_is_audited_against_the_parameters_in_force(tmp_path):
    """A jammer re-shapes uav1 -> bs0 to loss 0.4 during [1, 3) s of window 0 (its logged start
    and stop): that segment is held to the jammed loss, the rest of the window to the plan's 0."""
    from uavcas.events import AttackStart, AttackStop, attack_log_text
    from uavcas.twin.model import LinkOverride

    p = plan()
    jam = LinkOverride(attack_id="jamming-0", src="uav1", dst="bs0", start_s=1.0, stop_s=3.0, interference_dbm=-60.0,
                       sinr_db=3.0, mcs=0, rate_mbps=8.0, delay_ms=2.0, loss=0.4)
    p = p.model_copy(update={"windows": [p.windows[0].model_copy(update={"link_overrides": [jam]}), p.windows[1]]})
    tr = _steady(n=1200)  # 0.1 .. 4.9 s
    rng = np.random.default_rng(11)
    lost = {k for k, t in enumerate(tr.t_s) if 1.01 <= t < 2.99 and rng.random() < 0.4}
    rd = build(tmp_path, p, tr, drop=lambda h, k: h == 1 and k in lost)
    rd.attacks_jsonl.write_text(attack_log_text([
        AttackStart(attack_id="jamming-0", family="jamming", attackers=[], attacker_ips=[], victims=["uav1"],
                    victim_ips=["10.20.0.2"], t_unix=T0 + 1.0, params={}, planned_start_s=1.0, planned_stop_s=3.0),
        AttackStop(attack_id="jamming-0", family="jamming", t_unix=T0 + 3.0)]))
    f = audit(rd.root)
    segs = {x.segment: x for x in f.links if (x.src, x.dst, x.window) == ("uav1", "bs0", 0)}
    assert sorted(segs) == [0, 1, 2]
    assert segs[0].planned_loss == segs[2].planned_loss == 0.0 and segs[0].lost == segs[2].lost == 0
    on = segs[1]
    assert on.planned_loss == 0.4 and on.lost == len(lost) and on.loss_random == pytest.approx(0.4, abs=0.08)
    assert abs(on.loss_sigma) <= 3.0 and f.verdict == "pass"
    # the other direction and the other link are not split into a jammed setting
    assert {x.planned_loss for x in f.links if (x.src, x.dst) != ("uav1", "bs0")} == {0.0}
    # the same run judged without the reshape (no attack log): the losses break the plan's 0
    rd.attacks_jsonl.unlink()
    assert audit(rd.root).verdict == "fail"


def test_byte_identical_copies_in_a_queue_are_paired_in_order(tmp_path):
    # 20 ms of other frames queue on uav0 -> uav1, then five byte-identical frames (IP id 0, one
    # flow, 1 ms each at the rate) enter 2 ms apart and leave back to back behind them. Each
    # copy's step is 2 ms planned + its queue wait: pairing by the step closest to 2 ms swaps
    # them (main read 4 ms late and 3 ms early here).
    tr = Traffic()
    for k in range(20):
        tr.add(1.0, 1000, 6000)
    for k in range(5):
        tr.add(1.0005 + 0.002 * k, 1000, 7000, ip_id=0)
    f = audit(build(tmp_path, plan(), tr).root)
    assert f.packets == 25 and f.n == 50 and f.lost == 0 and f.loops == 0
    assert f.delay_error_max_ms < 0.002 and f.delay_error_p1_ms > -0.002 and f.verdict == "pass"


def _looped(tmp_path):
    """A steady flow, and one more frame that loops uav0 -> uav1 -> uav0 -> uav1 -> bs0 at 2 s while
    uav1's table sends bs0's traffic back to uav0 (2 ms per hop, the planned delay)."""
    from helpers.fidsynth import IPS, udp_frame

    frame = udp_frame(IPS["uav0"], IPS["bs0"], 4000, 9000, 777, 200)
    t = [T0 + 2.0 + 0.002 * k for k in range(5)]
    extra = {"uav0": [(t[0], frame), (t[2], frame)], "uav1": [(t[1], frame), (t[3], frame)], "bs0": [(t[4], frame)]}
    rd = build(tmp_path, plan(), _steady(), extra=extra)
    normal = rd.read_forwarding()
    loop = {**normal[0].next_hop, "uav1": {**normal[0].next_hop["uav1"], "bs0": "uav0"}}
    epochs = [normal[0], normal[0].model_copy(update={"t_begin_unix": t[0] + 0.001, "t_unix": t[0] + 0.001,
                                                      "next_hop": loop}),
              normal[0].model_copy(update={"t_begin_unix": t[2] + 0.001, "t_unix": t[2] + 0.001}), *normal[1:]]
    rd.forwarding_jsonl.write_text("".join(e.model_dump_json() + "\n" for e in epochs))
    return rd


def test_a_looping_frame_fails_the_audit(tmp_path):
    f = audit(_looped(tmp_path).root)
    assert f.loops == 1 and f.failed == ["loops"] and f.verdict == "fail"
    assert [c.value for c in f.checks if c.name == "loops"] == [1]
    looped = {(x.src, x.dst): x.loops for x in f.links if x.loops}
    assert looped == {("uav1", "uav0"): 1, ("uav0", "uav1"): 1}  # back to uav0, then to uav1 again
    assert f.packets == 401 and f.lost == 0 and f.delay_error_max_ms < 0.002  # its hops are still timed
    assert audit(_looped(tmp_path / "ok").root, Tolerances(loops=1)).verdict == "pass"


def test_a_frame_stamped_at_its_switch_after_it_reached_the_next_is_still_served_by_the_model(tmp_path):
    # Full frames on a 0.1 ms, 8 Mbit/s chain (1.514 ms a frame): one, then 19 more 0.13 ms later;
    # the first two leave at once (the bucket), the rest queue. The first is stamped at uav0
    # 0.12 ms late, after it reached uav1 (TCP frames here: the fabric keeps TCP's departure time,
    # so no switch stamps them on receipt), the others in order after it. Left split in two, it
    # was lost to the model, whose queue then ran one frame ahead of the emulator's: 18 crossings
    # one frame's serialisation late, p99 1.5 ms.
    tr = Traffic()
    tr.add(1.0, 1514, 6000)
    for k in range(19):
        tr.add(1.00013 + k * 1e-6, 1514, 6000)
    rd = build(tmp_path, plan(delay_ms=0.1), tr, stamp=lambda h, k: 1.2e-4 if (h, k) == (0, 0) else 0.0, tcp=True)
    f = audit(rd.root)
    assert f.packets == 20 and f.n == 40 and f.lost == 0 and f.late_over_1ms == 0.0 and f.verdict == "pass"
    # the late stamp reads as that frame (and the bucket's debt behind it) 0.12 ms early
    assert f.delay_error_max_ms < 0.002 and f.delay_error_p1_ms == pytest.approx(-0.12, abs=0.002)


def _burst_records(burst_b: int) -> str:
    return "".join(json.dumps({
        "window": w, "src": a, "dst": b, "port": "l", "backend": "htb-nft-nfqueue", "planned_rate_mbps": 8.0,
        "planned_delay_ms": 2.0, "planned_loss": 0.0, "applied_rate_mbps": 8.0, "applied_delay_ms": 2.0,
        "applied_loss": 0.0, "applied_burst_b": burst_b}) + "\n" for w in (0, 1) for a, b in (("uav0", "uav1"),
                                                                                            ("uav1", "bs0")))


def test_the_model_holds_the_bucket_depth_the_run_logged(tmp_path):
    # a kernel that held a 25 kB bucket at 8 Mbit/s (tc's default is 1600 B + rate/HZ without
    # high-resolution timers; a burst asked for): 20 frames of 1 kB every 0.5 s leave at once; a
    # model with this kernel's 1600 B would send them 1 ms apart and read them up to 19 ms early
    tr = Traffic()
    for b in range(8):
        for k in range(20):
            tr.add(0.2 + 0.5 * b, 1000, 6000)
    rd = build(tmp_path, plan(), tr, burst_b=25_000)
    rd.shaping_jsonl.write_text(_burst_records(25_000))
    f = audit(rd.root)
    assert f.verdict == "pass" and f.lost == 0 and abs(f.delay_error_p1_ms) < 0.002 and f.delay_error_max_ms < 0.002
    # a run that logged no depth is held to tc's default (runs made before it was logged)
    rd.shaping_jsonl.write_text("")
    old = audit(rd.root)
    assert old.delay_error_p1_ms < -5 and "delay_early_p1_ms" in old.failed
