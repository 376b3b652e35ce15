"""MAVLink command injection: token, payload rule, schedule, signing key, packet-exact truth."""

from __future__ import annotations

import pytest

from uavcas.attacks import ScenarioError, family
from uavcas.attacks.mavlink_inject import DEFAULT_SPEED_MPS, MavlinkInjectSpec
from uavcas.scenario import parse
from uavcas.twin.plan import plan

REST = "-6-2-telemetry-logdist-adaptive-random-30-95"


@pytest.mark.parametrize("tok, spec", [
    ("mavlink_inject=rtl", MavlinkInjectSpec(command="rtl")),
    ("mavlink_inject=land,n=5", MavlinkInjectSpec(command="land", count=5)),
    ("mavlink_inject=speed", MavlinkInjectSpec(command="speed", speed_mps=DEFAULT_SPEED_MPS)),
    ("mavlink_inject=speed,mps=0,hz=10,n=3", MavlinkInjectSpec(command="speed", speed_mps=0, rate_hz=10, count=3)),
])
def test_token_round_trips(tok, spec):
    got = family("mavlink_inject").parse(tok.partition("=")[2], tok)
    assert got == spec and got.token() == tok
    assert parse(tok + REST).to_string() == tok + REST
    assert family("mavlink_inject").spec_from_params(family("mavlink_inject").params(got)) == got


@pytest.mark.parametrize("text, match", [
    ("mavlink_inject", "needs a command"),
    ("mavlink_inject=fly", "not one of rtl, land, speed"),
    ("mavlink_inject=rtl,mps=3", "speed command only"),
    ("mavlink_inject=speed,mps=51", r"outside \[0, 50\]"),
    ("mavlink_inject=rtl,hz=0", r"outside \[1, 100\]"),
    ("mavlink_inject=rtl,x=1", "not one of mps=, hz=, n="),
    ("mavlink_inject=rtl,n=1,n=2", "given twice"),
    ("mavlink_inject=speed,mps=20", "not in canonical form"),
])
def test_bad_tokens_are_one_line_errors(text, match):
    with pytest.raises(ScenarioError, match=match) as e:
        parse(text + REST)
    assert "\n" not in str(e.value)


def test_refused_on_a_payload_without_mavlink():
    with pytest.raises(ScenarioError, match="needs payload telemetry or video or mixed .*got 'image'") as e:
        parse("mavlink_inject=rtl-6-2-image-logdist-adaptive-random-30-95")
    assert "\n" not in str(e.value)
    for payload in ("telemetry", "video", "mixed"):
        parse(f"mavlink_inject=rtl-6-2-{payload}-logdist-adaptive-random-30-95")
    # composable with a flood (no longer "two floods") and with the stealth families
    assert parse("dos=1000+mavlink_inject=land" + REST).to_string() == "dos=1000+mavlink_inject=land" + REST
    with pytest.raises(ScenarioError, match="ddos and dos cannot be combined"):
        parse("ddos=1000+dos=1000" + REST)


def test_plan_is_seeded_and_routes_the_attacker_to_the_victim():
    cfg = "mavlink_inject=speed,mps=5" + REST
    a, b, c = plan(cfg, seed=7, windows=4), plan(cfg, seed=7, windows=4), plan(cfg, seed=8, windows=4)
    assert a.model_dump_json() == b.model_dump_json() and a.model_dump_json() != c.model_dump_json()
    (att,) = a.attacks
    assert len(att.attackers) == 1 and att.attackers[0] not in att.victims
    assert att.params == {"command": "speed", "speed_mps": 5, "rate_hz": 2, "count": 0}
    inside = [w for w in a.windows if w.t_s < att.stop_s and w.t_s + a.window_s > att.start_s]
    assert all(any(r.src == att.attackers[0] and r.dst == att.victims[0] for r in w.routes) for w in inside)


def test_signing_key_is_32_bytes_and_deterministic():
    from uavcas.traffic.mavlink import signing_key, signing_spec

    k = signing_key(7, "mavlink_inject=rtl" + REST)
    assert len(k) == 32 and k == signing_key(7, "mavlink_inject=rtl" + REST)
    assert k != signing_key(8, "mavlink_inject=rtl" + REST) and k != signing_key(7, "benign" + REST)
    assert signing_spec(7, "mavlink_inject=rtl" + REST).key == k


# Hand-built packets (tests/helpers/hand_truth.py): uav1 forges commands to uav0:14550 in [20, 30).
def _inject_run():
    from helpers.hand_truth import icmp_error, pkt

    def udp(t, src, dst, sport, dport, **kw):
        return pkt(t, src, dst, sport, dport, proto=17, ip_id=0, payload=kw.pop("payload", 41), **kw)

    forged = udp(21.0, "uav1", "uav0", 40000, 14550)
    return {
        "forged": forged,
        "forged_lost": udp(25.0, "uav1", "uav0", 40000, 14550, at=["uav1"]),  # lost on the way: still forged
        "ack": udp(21.01, "uav0", "uav1", 14550, 40000, payload=22),
        # the victim's ack to the last forged frame, after the stop: still its answer
        "late_ack": udp(30.2, "uav0", "uav1", 14550, 40000, payload=22),
        "icmp_forged": icmp_error(21.5, "uav0", "uav1", forged),  # the victim's port unreachable, quoting a frame
        "icmp": icmp_error(26.0, "uav1", "uav0", dict(forged, t=26.0, src="uav0", dst="uav1", sport=14550,
                                                      dport=40000)),  # quotes an ack, not a frame: benign
        # the same hosts and port outside the window, and other traffic in it: benign
        "before": udp(19.9, "uav1", "uav0", 40000, 14550),
        "after": udp(30.1, "uav1", "uav0", 40000, 14550),
        "other_port": udp(22.0, "uav1", "uav0", 40000, 5600),
        "victim_to_bs": udp(22.0, "uav0", "bs0", 14550, 14550),
        "bs_to_victim": udp(22.5, "bs0", "uav0", 14550, 14550),
        # an answer before anything was forged on that 5-tuple
        "early": udp(20.5, "uav0", "uav1", 14550, 40000, payload=22),
    }


def test_forged_frames_and_their_acks_are_labelled_packet_exact():
    from helpers.hand_truth import context, rows_of, window
    from uavcas.labels.effects import packet_truth
    from uavcas.vocabulary import FAMILIES

    p = _inject_run()
    ctx = context(list(p.values()), [window("mavlink_inject", "uav1", "uav0", 20.0, 30.0)])
    truth = packet_truth(ctx)

    def effects(name):
        rows = rows_of(ctx, p[name])
        return set(truth.effect_names(rows)), set(truth.family[rows].tolist())

    k = FAMILIES.index("mavlink_inject")
    for name in ("forged", "forged_lost"):
        assert effects(name) == ({"mavlink_inject"}, {k}), name
    for name in ("ack", "late_ack", "icmp_forged"):
        assert effects(name) == ({"provoked"}, {k}), name
    for name in ("icmp", "before", "after", "other_port", "victim_to_bs", "bs_to_victim", "early"):
        assert effects(name) == ({"benign"}, {-1}), name


@pytest.mark.slow  # 5 s on 2 cores
def test_run_refuses_signing_on_a_payload_without_mavlink(tmp_path):
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "uavcas", "run", "blackhole-6-2-image-logdist-adaptive-random-30-95",
                        "--mavlink-signing", "--out", str(tmp_path / "run")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and "--mavlink-signing: payload 'image' carries no MAVLink" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "run").exists()
