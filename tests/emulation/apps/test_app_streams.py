"""The apps' random draws (no root): each client and video on its own named stream of
the plan's seed (`uavcas.seeding`), the same on a rerun, unrelated between consumers."""

from __future__ import annotations

import numpy as np

from uavcas.emulation.apps import client, images
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


