"""The apps' random draws (no root): each client, video and replayer on its own named stream of
the plan's seed (`uavcas.seeding`), the same on a rerun, unrelated between consumers."""

from __future__ import annotations

import numpy as np
from scapy.layers.inet import IP, TCP
from scapy.layers.l2 import Ether

from uavcas.emulation.apps import client, images, replayer
from uavcas.emulation.apps.traffic import BenignTraffic
from uavcas.twin.plan import plan

IMAGES = tuple(f"img{k:03d}.jpg" for k in range(24))


def _client(tmp_path, seed: int, index: int, **kw) -> client.ClientSpec:
    return client.ClientSpec("bs0", "uav0", "10.9.0.1", IMAGES, 10.0, tmp_path / "log.tsv", seed=seed, index=index,
                             **kw)


def test_a_clients_draws_repeat_for_its_seed_and_index(tmp_path):
    order, thinks = client.draw_sequence(_client(tmp_path, 5, 2))
    again, thinks_again = client.draw_sequence(_client(tmp_path, 5, 2))
    assert order == again and np.array_equal(thinks, thinks_again)
    assert len(order) == client.SEQUENCE_LEN and set(order) <= set(IMAGES) and len(set(order)) > 12
    assert np.all((thinks >= 0.05) & (thinks <= 4 * client.THINK_MEAN_S))
    assert client.render_script(_client(tmp_path, 5, 2)).count(order[0]) >= 1


def test_clients_draw_unrelated_streams(tmp_path):
    seen = {tuple(client.draw_sequence(_client(tmp_path, s, k))[0]) for s, k in [(0, 0), (0, 1), (1, 0), (0, 1000)]}
    assert len(seen) == 4  # seed*1000+k made (0, 1000) and (1, 0) one stream


def test_the_runs_clients_take_the_plans_seed_and_their_index(tmp_path):
    p = plan("benign-4-2-image-logdist-adaptive-random-30-95", seed=7, windows=1)
    specs = BenignTraffic(None, p, tmp_path, 5.0).client_specs(list(IMAGES), 0.0)
    assert [(s.bs, s.uav, s.seed, s.index) for s in specs] == [
        ("bs0", "uav0", 7, 0), ("bs1", "uav1", 7, 1), ("bs0", "uav2", 7, 2), ("bs1", "uav3", 7, 3)]
    orders = [client.draw_sequence(s)[0] for s in specs]
    assert all(a != b for i, a in enumerate(orders) for b in orders[i + 1:])


def test_video_seeds_differ_from_the_http_clients_stream(tmp_path):
    p = plan("benign-4-2-video-logdist-adaptive-random-30-95", seed=7, windows=1)
    t = BenignTraffic(None, p, tmp_path, 5.0)
    seeds = [t._video_spec("bs0", k).seed for k in range(4)]
    assert seeds == [BenignTraffic(None, p, tmp_path, 5.0)._video_spec("bs0", k).seed for k in range(4)]
    assert len(set(seeds)) == 4
    other = BenignTraffic(None, plan("benign-4-2-video-logdist-adaptive-random-30-95", seed=8, windows=1),
                          tmp_path, 5.0)
    assert seeds != [other._video_spec("bs0", k).seed for k in range(4)]


def test_image_sizes_and_bytes_repeat_for_a_seed(tmp_path):
    assert images.image_sizes(3, 8) == images.image_sizes(3, 8) != images.image_sizes(4, 8)
    a = images.generate(tmp_path / "a", 3, 2)
    b = images.generate(tmp_path / "b", 4, 2)
    assert (tmp_path / "a" / "img000.jpg").read_bytes() != (tmp_path / "b" / "img000.jpg").read_bytes()
    assert a != b


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
