"""The `Channel` chain: consistency, determinism, and that the physics changes the links."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.channel import Channel, LinkArrays
from uavcas.channel.pathloss import UMaAV

BS_MAST_M = 25.0


def _scene(rng: np.random.Generator, n_uav: int, n_bs: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """The paper campaign's geometry: UAVs in 1000 x 1000 x [30, 110] m, BSs on 25 m masts."""
    uav = rng.uniform([0, 0, 30], [1000, 1000, 110], (n_uav, 3))
    bs = np.c_[rng.uniform(100, 900, (n_bs, 2)), np.full(n_bs, BS_MAST_M)]
    return np.vstack([uav, bs]), np.r_[np.zeros(n_uav, bool), np.ones(n_bs, bool)]


def _nearest_links(pos: np.ndarray, is_bs: np.ndarray) -> np.ndarray:
    """Each UAV to its nearest node (UAV or BS) and to its nearest BS (the bridge candidate)."""
    d = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    np.fill_diagonal(d, np.inf)
    uavs = np.flatnonzero(~is_bs)
    bss = np.flatnonzero(is_bs)
    nearest = d[uavs].argmin(axis=1)
    nearest_bs = bss[d[np.ix_(uavs, bss)].argmin(axis=1)]
    pairs = np.r_[np.c_[uavs, nearest], np.c_[uavs, nearest_bs]]
    pairs = np.sort(pairs, axis=1)
    return np.unique(pairs, axis=0)


def _campaign(pathloss: str, tx_dbm: float, n_runs: int = 24, windows: int = 4) -> LinkArrays:
    """Pool the links of a small campaign: swarm sizes 5..20, several windows with motion."""
    rng = np.random.default_rng(2024)
    parts = []
    for run in range(n_runs):
        n_uav = (5, 10, 15, 20)[run % 4]
        pos, is_bs = _scene(rng, n_uav)
        ch = Channel(n_nodes=len(pos), pathloss=pathloss, tx_power_dbm=tx_dbm, noise_dbm=-95.0, seed=run)
        for _ in range(windows):
            pos[:n_uav] += rng.normal(0, 20, (n_uav, 3)) * [1, 1, 0.2]
            pos[:n_uav] = np.clip(pos[:n_uav], [0, 0, 30], [1000, 1000, 110])
            parts.append(ch.evaluate(pos, _nearest_links(pos, is_bs), is_bs))
    return LinkArrays(**{
        f: (None if getattr(parts[0], f) is None else np.concatenate([getattr(p, f) for p in parts]))
        for f in LinkArrays.__dataclass_fields__
    })


@pytest.mark.parametrize("pathloss", ["logdist", "3gpp"])
def test_physics_matters_across_the_paper_campaign(pathloss):
    low, high = _campaign(pathloss, 10.0), _campaign(pathloss, 30.0)
    # Same geometry for both powers (same seeds), spanning short to long links.
    np.testing.assert_array_equal(low.distance_m, high.distance_m)
    assert low.distance_m.min() < 30 and low.distance_m.max() > 400
    levels = np.union1d(np.unique(low.mcs), np.unique(high.mcs))
    assert len(levels) >= 4, levels
    assert len(np.unique(low.mcs)) >= 4, np.unique(low.mcs)  # even a single power setting
    # +20 dB of TX power raises the mean rate materially and never lowers a link's MCS.
    assert high.rate_mbps.mean() > 1.2 * low.rate_mbps.mean()
    assert np.all(high.mcs >= low.mcs)
    np.testing.assert_allclose(high.snr_db - low.snr_db, 20.0)
    # And loss and channel time respond too: the weak links at 10 dBm are worse.
    assert low.loss.mean() > high.loss.mean() and low.mac_time_us.mean() > high.mac_time_us.mean()


def test_rate_falls_with_distance():
    # One BS, UAVs at 60 m on a line; free space has no shadowing, so the trend is exact.
    d = np.array([20.0, 100.0, 250.0, 500.0, 900.0])
    pos = np.vstack([[[0, 0, BS_MAST_M]], np.c_[d, np.zeros(5), np.full(5, 60.0)]])
    pairs = np.c_[np.zeros(5, int), np.arange(1, 6)]
    ch = Channel(n_nodes=6, pathloss="freespace", tx_power_dbm=10.0)
    arr = ch.evaluate(pos, pairs, np.r_[True, np.zeros(5, bool)])
    assert np.all(np.diff(arr.pathloss_db) > 0) and np.all(np.diff(arr.snr_db) < 0)
    assert np.all(np.diff(arr.mcs) <= 0) and arr.mcs[0] == 6 and arr.mcs[-1] < 6
    assert np.all(np.diff(arr.rate_mbps) <= 0)
    # Without fading the loss is a step: negligible in range, ~1 beyond (500 m at 10 dBm: SNR 7.7 dB).
    assert np.all(arr.loss[:3] < 1e-6) and np.all(arr.loss[3:] > 0.5)
    fixed = Channel(n_nodes=6, pathloss="freespace", tx_power_dbm=10.0, modulation=0).evaluate(
        pos, pairs, np.r_[True, np.zeros(5, bool)])
    assert np.all(np.diff(fixed.per) > 0) and np.all(np.diff(fixed.mac_time_us) >= 0)
    assert fixed.mac_time_us[-1] > fixed.mac_time_us[0]


def test_link_arrays_are_consistent():
    rng = np.random.default_rng(7)
    pos, is_bs = _scene(rng, 10)
    iu = np.triu_indices(len(pos), 1)
    pairs = np.c_[iu]
    ch = Channel(n_nodes=len(pos), pathloss="logdist", tx_power_dbm=30.0, noise_dbm=-95.0, seed=3)
    arr = ch.evaluate(pos, pairs, is_bs)
    assert len(arr) == len(pairs) and arr.los is None
    np.testing.assert_allclose(arr.snr_db, 30.0 - arr.pathloss_db + 95.0)
    np.testing.assert_allclose(arr.distance_m, np.linalg.norm(pos[pairs[:, 0]] - pos[pairs[:, 1]], axis=1))
    assert np.all(arr.d2d_m <= arr.distance_m + 1e-9)
    assert np.all((arr.loss >= 0) & (arr.loss <= 1)) and np.all(arr.rate_mbps > 0)
    assert arr.shadow_db.std() == pytest.approx(4.0, abs=0.8)  # sigma(h) is 3.7-4.5 dB


def test_deterministic_per_seed_and_sequential():
    rng = np.random.default_rng(1)
    pos, is_bs = _scene(rng, 8)
    pairs = np.c_[np.triu_indices(len(pos), 1)]
    moved = pos + np.r_[np.full((8, 3), 15.0), np.zeros((2, 3))]

    def run(seed):
        ch = Channel([f"n{i}" for i in range(len(pos))], pathloss="3gpp", seed=seed)
        return ch.evaluate(pos, pairs, is_bs), ch.evaluate(moved, pairs, is_bs)

    (a1, a2), (b1, b2), (c1, _) = run(5), run(5), run(6)
    for x, y in ((a1, b1), (a2, b2)):
        for f in LinkArrays.__dataclass_fields__:
            np.testing.assert_array_equal(getattr(x, f), getattr(y, f))
    assert not np.allclose(a1.shadow_db, c1.shadow_db)
    # Windows are correlated, not redrawn: dd = 15 sqrt(3) m per UAV end.
    r = np.corrcoef(a1.shadow_db / (a1.shadow_db.std()), a2.shadow_db / a2.shadow_db.std())[0, 1]
    assert 0.3 < r < 0.95


def test_3gpp_geometry_uses_mast_and_altitude():
    # BS at 25 m, UAV at 30 m, 500 m away: the TR 36.777 spec geometry.
    pos = np.array([[0.0, 0.0, 25.0], [500.0, 0.0, 30.0], [0.0, 500.0, 90.0]])
    ch = Channel(n_nodes=3, pathloss="3gpp", sample_los=False, seed=0)
    arr = ch.evaluate(pos, np.array([[0, 1]]), np.array([True, False, False]))
    m = UMaAV()
    expected = m.loss_expected_db(500.0, np.hypot(500.0, 5.0), 30.0)
    assert float(arr.pathloss_db[0] - arr.shadow_db[0]) == pytest.approx(float(expected), abs=1e-9)
    # Sampled LOS state: booleans; the UAV-UAV link is always LOS.
    ch = Channel(n_nodes=3, pathloss="3gpp", seed=0)
    arr = ch.evaluate(pos, np.array([[0, 1], [1, 2]]), np.array([True, False, False]))
    assert arr.los.dtype == bool and bool(arr.los[1])
    assert float(arr.pathloss_db[1] - arr.shadow_db[1]) == pytest.approx(
        float(m.loss_los_db(np.linalg.norm(pos[1] - pos[2]), 90.0)))


def test_los_state_frequency_matches_probability_and_persists():
    # 300 UAVs at 30 m on a 600 m ring around one BS: P_LOS = 0.7746 for every link.
    n = 300
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    pos = np.vstack([np.c_[600 * np.cos(ang), 600 * np.sin(ang), np.full(n, 30.0)], [[0, 0, 25.0]]])
    is_bs = np.r_[np.zeros(n, bool), True]
    pairs = np.c_[np.arange(n), np.full(n, n)]
    ch = Channel(n_nodes=n + 1, pathloss="3gpp", seed=2)
    states = [ch.evaluate(pos, pairs, is_bs).los for _ in range(3)]
    p = float(UMaAV().p_los_at(600.0, 30.0))
    assert states[0].mean() == pytest.approx(p, abs=0.07)
    np.testing.assert_array_equal(states[0], states[2])  # nodes did not move: state kept


def test_fixed_mcs_and_inputs_validated():
    pos = np.array([[0.0, 0.0, 25.0], [50.0, 0.0, 60.0], [800.0, 0.0, 60.0]])
    is_bs = np.array([True, False, False])
    ch = Channel(n_nodes=3, modulation="mcs6", tx_power_dbm=10.0)
    arr = ch.evaluate(pos, np.array([[0, 1], [0, 2]]), is_bs)
    assert arr.mcs.tolist() == [6, 6] and arr.loss[1] > arr.loss[0]
    assert Channel(n_nodes=3, modulation=2).evaluate(pos, np.array([[0, 1]]), is_bs).mcs.tolist() == [2]
    ch = Channel(n_nodes=3)
    empty = ch.evaluate(pos, np.zeros((0, 2), int), is_bs)
    assert len(empty) == 0 and empty.rate_mbps.shape == (0,)
    with pytest.raises(ValueError):
        ch.evaluate(pos[:2], np.array([[0, 1]]), is_bs)
    with pytest.raises(ValueError):
        ch.evaluate(pos, np.array([[0, 3]]), is_bs)
    with pytest.raises(ValueError):
        ch.evaluate(pos, np.array([[1, 1]]), is_bs)
    with pytest.raises(ValueError):
        Channel(["a", "b"], n_nodes=3)
    with pytest.raises(ValueError):
        Channel(n_nodes=3, modulation="mcs9")


def test_fading_makes_loss_rise_smoothly_with_distance():
    from uavcas.channel import TR36777_UMA_AV_K

    d = np.linspace(50.0, 3000.0, 300)
    pos = np.vstack([[[0, 0, BS_MAST_M]], np.c_[d, np.zeros(d.size), np.full(d.size, 60.0)]])
    pairs = np.c_[np.zeros(d.size, int), np.arange(1, d.size + 1)]
    is_bs = np.r_[True, np.zeros(d.size, bool)]
    flat = Channel(n_nodes=d.size + 1, pathloss="freespace", tx_power_dbm=0.0).evaluate(pos, pairs, is_bs)
    faded = Channel(n_nodes=d.size + 1, pathloss="freespace", tx_power_dbm=0.0,
                    fading=TR36777_UMA_AV_K).evaluate(pos, pairs, is_bs)
    mid = lambda a: np.count_nonzero((a.loss > 0.01) & (a.loss < 0.99))  # noqa: E731
    assert mid(faded) > 5 * max(mid(flat), 1)  # a transition zone instead of a cliff
    np.testing.assert_allclose(faded.k_db, 4.217 * np.log10(60.0) + 5.787)
    assert faded.loss[-1] > 0.99 and faded.loss[0] < 0.01
