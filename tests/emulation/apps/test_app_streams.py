"""The replayer's random draws (no root): each replayer on its own named stream of the plan's seed
(`uavcas.seeding`), the same on a rerun, unrelated between attackers. (The benign apps' draws
are in tests/traffic/test_traffic_image.py.)"""

from __future__ import annotations

from scapy.layers.inet import IP, TCP
from scapy.layers.l2 import Ether

from uavcas.emulation.apps import replayer


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
    import subprocess
    import sys
    from types import SimpleNamespace

    from uavcas.attacks import family
    from uavcas.attacks.replay import ReplaySpec

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
    got = [(node, replayer.parse_args(argv[3:])) for node, argv in started]
    assert [(node, a.seed, a.index, a.seq_mode) for node, a in got] == [
        ("uav2", 2**32 - 1, 2, "rand"), ("uav3", 2**32 - 1, 3, "rand")]
