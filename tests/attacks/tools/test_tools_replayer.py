"""The replayer (`attacks/tools/replayer.py`) without root: parsing, the seq modes, buffering and
pacing, and its random draws on its own stream of the plan's seed (`uavcas.seeding`)."""

from __future__ import annotations

import subprocess
import sys
from types import SimpleNamespace

from scapy.layers.inet import IP, TCP, UDP
from scapy.layers.l2 import Ether

from uavcas import seeding
from uavcas.attacks import family
from uavcas.attacks.replay import ReplaySpec
from uavcas.attacks.tools import replayer, tool_path


def _frame(src="10.9.0.3", dst="10.9.0.9", ttl=64, seq=1000, ip_id=7, payload=b"x" * 100) -> bytes:
    return bytes(Ether(src="02:00:00:00:00:03", dst="02:00:00:00:00:09") / IP(src=src, dst=dst, ttl=ttl, id=ip_id)
                 / TCP(sport=80, dport=40000, seq=seq, flags="PA") / payload)


def test_replay_parse_and_mutate_seq_modes():
    s = replayer.parse(_frame())
    assert (s.src, s.dst, s.proto, s.sport, s.dport, s.ip_id, s.ttl, s.seq) == (
        "10.9.0.3", "10.9.0.9", 6, 80, 40000, 7, 64, 1000)
    rng = seeding.generator(1, "replayer", 0)
    out, seq = replayer.mutate(_frame(), 3, "inc", 5, rng)
    p = Ether(out)
    assert p[IP].ttl == 59 and p[TCP].seq == 1003 == seq and p[IP].id == 7
    assert IP(bytes(p[IP])).chksum == Ether(bytes(p))[IP].chksum  # valid checksum after rebuild
    rebuilt = Ether(out)
    del rebuilt[IP].chksum
    del rebuilt[TCP].chksum
    assert Ether(bytes(rebuilt))[TCP].chksum == p[TCP].chksum
    assert replayer.mutate(_frame(), 3, "zero", 5, rng)[1] == 1000
    assert replayer.new_seq(0xFFFFFFFF, 2, "inc", rng) == 1
    seqs = {replayer.mutate(_frame(), 1, "rand", 3, rng)[1] for _ in range(5)}
    assert len(seqs) == 5
    udp = bytes(Ether() / IP(src="10.9.0.3", dst="10.9.0.1", ttl=64) / UDP(sport=1, dport=2) / b"hi")
    out, seq = replayer.mutate(udp, 1, "inc", 5, rng)
    assert seq is None and Ether(out)[IP].ttl == 59


def test_replayer_buffers_victim_traffic_paces_and_never_replays_itself():
    r = replayer.Replayer("10.9.0.3", "10.9.0.5", buffer_pkts=3, delay_ms=200, rate_pps=10, ttl_dec=5,
                          seq_mode="inc")
    assert not r.observe(0.0, _frame(src="10.9.0.7", dst="10.9.0.8"))  # not the victim's
    assert not r.observe(0.0, _frame(src="10.9.0.5", dst="10.9.0.3"))  # the attacker's own
    assert not r.observe(0.0, _frame(), outgoing=True)  # what we sent ourselves
    for k in range(5):
        assert r.observe(0.01 * k, _frame(ip_id=k, seq=1000 + k)) == (k < 3)
    assert len(r.buffer) == 3 and r.stats["buffer_full"] == 2  # a full buffer admits nothing new
    assert not r.due(0.1)  # not before the delay
    assert r.due(0.25)
    out, rec = r.next_injection(0.25)
    assert rec["ip_id"] == 0 and rec["ttl"] == 59 and rec["seq"] == 1000 + 1 and rec["orig_seq"] == 1000
    assert not r.due(0.26)  # paced: next one 100 ms later
    assert r.due(0.36)
    assert r.observe(0.3, _frame(ip_id=10, seq=2000))  # a slot was freed
    assert not r.observe(0.3, out)  # our injection coming back through the mirror
    assert not r.observe(0.3, _frame(ttl=59, ip_id=99))  # a TTL only our injections carry
    assert r.stats["own_ignored"] == 2
    _, rec2 = r.next_injection(0.36)
    assert rec2["seq"] == 1001 + 2  # k counts injections


def test_replayer_buffers_and_replays_a_udp_stream_with_ip_id_0_and_the_ttl_kept():
    """MAVLink from an unconnected socket: IP id 0 on every datagram. With ttl_dec 0 only the bytes
    tell our copy (coming back through the mirror) from the stream's next datagram."""
    def mav(seq: int) -> bytes:
        return bytes(Ether() / IP(src="10.9.0.3", dst="10.9.1.1", ttl=64, id=0)
                     / UDP(sport=14555, dport=14550) / (bytes([0xFD, 9, 0, 0, seq, 1, 1, 0, 0, 0]) + bytes(11)))

    r = replayer.Replayer("10.9.0.3", "10.9.0.5", buffer_pkts=5, delay_ms=0, rate_pps=100, ttl_dec=0,
                          seq_mode="inc")
    assert r.observe(0.0, mav(0))
    out, rec = r.next_injection(0.0)
    assert (rec["protocol"], rec["src_port"], rec["dst_port"], rec["ip_id"], rec["ttl"], rec["seq"]) == (
        17, 14555, 14550, 0, 64, None)
    assert Ether(out)[UDP].payload.load == Ether(mav(0))[UDP].payload.load  # the datagram as it was
    assert not r.observe(0.01, out)  # our copy, back through the mirror
    assert r.observe(0.1, mav(1))  # the stream's next datagram: same header fields, other bytes
    assert r.stats["own_ignored"] == 1 and r.stats["buffered"] == 2



def _rand_seqs(seed: int, index: int, n: int = 6) -> list[int]:
    r = replayer.Replayer("10.9.0.3", "10.9.0.5", buffer_pkts=n, delay_ms=0, rate_pps=1000, ttl_dec=1,
                          seq_mode="rand", seed=seed, index=index)
    for k in range(n):
        frame = bytes(Ether() / IP(src="10.9.0.3", dst="10.9.0.9", id=k) / TCP(sport=80, dport=40000, seq=1000 + k))
        assert r.observe(0.0, frame)
    return [r.next_injection(1.0 + k)[1]["seq"] for k in range(n)]


def test_a_replayers_random_seqs_repeat_per_plan_seed_and_attacker():
    a = _rand_seqs(3, 1)
    assert a == _rand_seqs(3, 1) and len(set(a)) == len(a) and all(0 <= s < 2**32 for s in a)
    assert a != _rand_seqs(3, 2) and a != _rand_seqs(4, 1)
    assert _rand_seqs(0, 1000) != _rand_seqs(1, 0)  # seed*1000+index made these one stream


def test_the_replay_family_starts_each_replayer_on_the_plans_seed_and_its_index(tmp_path):
    """Replay.prepare without root: a fake executor records the replayer's argv (a stand-in
    process says "ready"), which the replayer's own parser reads back."""
    started = []

    def popen(node, argv, timeout_s, **kw):
        started.append((node, argv))
        return subprocess.Popen([sys.executable, "-c", "import time; print('ready', flush=True); time.sleep(60)"],
                                **kw)

    nodes = {"uav0": 0, "uav2": 2, "uav3": 3}
    ex = SimpleNamespace(spec=lambda a: ReplaySpec(buffer_pkts=10, delay_ms=100, rate_pps=20, ttl_dec=3,
                                                   seq_mode="rand"),
                         log_dir=tmp_path, ip=lambda n: f"10.77.1.{nodes[n] + 1}", duration_s=5.0,
                         plan=SimpleNamespace(seed=2**32 - 1), index=nodes.__getitem__,
                         emu=SimpleNamespace(popen=popen), state={}, add_process=lambda proc, log: None)
    attack = SimpleNamespace(attackers=["uav2", "uav3"], victims=["uav0"], attack_id="a0", family="replay")
    try:
        family("replay").prepare(ex, attack)
    finally:
        for proc in ex.state.values():
            proc.popen.kill()
            proc.popen.wait(10)
    assert all(argv[1] == str(tool_path("replayer")) for _, argv in started)
    got = [(node, replayer.parse_args(argv[2:])) for node, argv in started]
    assert [(node, a.seed, a.index, a.seq_mode) for node, a in got] == [
        ("uav2", 2**32 - 1, 2, "rand"), ("uav3", 2**32 - 1, 3, "rand")]

