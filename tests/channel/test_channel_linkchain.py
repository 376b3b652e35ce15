"""One link chain (`uavcas.channel.linkchain`): `uavcas channel predict` and the twin's plans give
the same per-link values, so the two consumers cannot drift apart.

* A real plan with free space (no shadowing, no LOS state: the twin's loss is the model's median,
  which is what `channel predict` evaluates): `channel predict` on every node pair's geometry,
  read off the plan's positions, gives each air link's path loss, SNR, MCS and loss, and its
  single-link rates shared over the hearing matrix of its output give the plan's rates.
* The quick preset's log-distance and 3GPP plans (shadowing, LOS states, fading): the chain on
  each air link's recorded path loss gives the link's SNR, MCS and loss.

The plan rounds positions to the millimetre, losses to 1e-3 dB and loss to 1e-8, hence the
tolerances; a setting one consumer read and the other did not (gain, noise, fading, MCS rule,
link layer, carrier sense) moves the values by far more.
"""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from uavcas.channel import LinkChain, LinkGeometry
from uavcas.cli import app
from uavcas.scenario import manifest
from uavcas.twin.plan import plan
from uavcas.twin.profile import load_profile

DB_TOL = 5e-3  # mm positions and 1e-3 dB rounding
LOSS_TOL = 1e-3
RATE_REL = 1e-3


def _pair_geometry(p, w) -> pd.DataFrame:
    """Every node pair of window w, as `channel predict` reads a geometry (the lower end as h_bs_m)."""
    pos = {k: np.array(v) for k, v in p.windows[w].positions.items()}
    rows = []
    for a, b in itertools.combinations([nd.name for nd in p.nodes], 2):
        pa, pb = pos[a], pos[b]
        lo, hi = sorted((pa[2], pb[2]))
        rows.append({"a": a, "b": b, "d3d_m": float(np.linalg.norm(pa - pb)),
                     "d2d_m": float(np.linalg.norm(pa[:2] - pb[:2])), "h_uav_m": hi, "h_bs_m": lo})
    return pd.DataFrame(rows)


@pytest.mark.parametrize("profile, tx_dbm", [("calibrated", 30), ("paper", 10)])
def test_channel_predict_gives_the_plans_link_values(tmp_path, profile, tx_dbm):
    p = plan(f"benign-6-2-mixed-freespace-adaptive-random-{tx_dbm}-95", seed=0, windows=3, profile=profile)
    prof = load_profile(profile)
    chain = LinkChain.build(tx_power_dbm=p.scenario.tx_dbm, noise_dbm=p.scenario.noise_dbm, **prof.chain_kwargs())
    names = [nd.name for nd in p.nodes]
    packet_bits = 8 * prof.channel.link_layer.packet_bytes
    checked, levels, contended = 0, set(), 0
    for w, window in enumerate(p.windows):
        src, out = tmp_path / f"geom{w}.csv", tmp_path / f"pred{w}.csv"
        _pair_geometry(p, w).to_csv(src, index=False)
        r = CliRunner().invoke(app, ["channel", "predict", "--model", "freespace", "--in", str(src), "--out", str(out),
                                     "--profile", profile, "--tx-dbm", str(p.scenario.tx_dbm),
                                     "--noise-dbm", str(p.scenario.noise_dbm)])
        assert r.exit_code == 0, r.output
        pred = pd.read_csv(out).set_index(["a", "b"])
        pairs = np.array([(names.index(a), names.index(b)) for a, b in pred.index])
        hears = chain.hears(len(names), pairs, pred["pathloss_db"].to_numpy())
        air = [lk for lk in window.links if lk.kind == "air"]
        got = pred.loc[[(lk.a, lk.b) for lk in air]]
        single = got["rate_mbps"].to_numpy()
        ends = np.array([(names.index(lk.a), names.index(lk.b)) for lk in air])
        shared = chain.shared_rate_mbps(ends, packet_bits / single, hears)  # E[T] = 8 L / single-link rate
        for lk, (_, row), rate, alone in zip(air, got.iterrows(), shared, single):
            assert row["pathloss_db"] == pytest.approx(lk.pathloss_db, abs=DB_TOL), (w, lk)
            assert row["snr_db"] == pytest.approx(lk.snr_db, abs=DB_TOL), (w, lk)
            assert int(row["mcs"]) == lk.mcs, (w, lk)
            assert row["loss"] == pytest.approx(lk.loss, abs=LOSS_TOL), (w, lk)
            assert rate == pytest.approx(lk.rate_mbps, rel=RATE_REL), (w, lk)
            checked += 1
            levels.add(lk.mcs)
            contended += rate < alone * (1 - RATE_REL)
    # the comparison covers several MCS levels and links whose rate the airtime sharing cut
    assert checked >= 15 and len(levels) >= 2 and contended >= 1, (checked, levels, contended)


@pytest.mark.parametrize("pathloss", ["logdist", "3gpp"])
def test_the_chain_on_a_quick_plans_loss_gives_its_links(pathloss):
    e = next(x for x in manifest("quick", seed=0) if f"-{pathloss}-" in x.config)
    p = plan(e.config, seed=e.seed, windows=e.windows, window_s=e.window_s, rounds=e.rounds)
    prof = load_profile(None)
    chain = LinkChain.build(tx_power_dbm=p.scenario.tx_dbm, noise_dbm=p.scenario.noise_dbm, **prof.chain_kwargs())
    air = [(w, lk) for w in p.windows for lk in w.links if lk.kind == "air"]
    lo_hi = [sorted((w.positions[lk.a][2], w.positions[lk.b][2])) for w, lk in air]
    d3d = np.array([lk.distance_m for _, lk in air])
    d2d = np.array([np.hypot(*np.subtract(w.positions[lk.a][:2], w.positions[lk.b][:2])) for w, lk in air])
    geom = LinkGeometry(d3d_m=d3d, d2d_m=d2d, h_ground_m=np.array([x[0] for x in lo_hi]),
                        h_air_m=np.array([x[1] for x in lo_hi]), air_to_air=np.zeros(len(air), dtype=bool))
    got = chain.links(geom, np.array([lk.pathloss_db for _, lk in air]))
    np.testing.assert_allclose(got.snr_db, [lk.snr_db for _, lk in air], atol=DB_TOL)
    np.testing.assert_array_equal(got.mcs, [lk.mcs for _, lk in air])
    np.testing.assert_allclose(got.loss, [lk.loss for _, lk in air], atol=LOSS_TOL)
    assert len(air) >= 10 and len(set(got.mcs.tolist())) >= 2


def test_a_chain_setting_moves_predict_away_from_the_plan():
    """The comparison above can fail: a chain that drops the profile's fading (one setting)
    no longer reproduces the plan's links."""
    p = plan("benign-6-2-mixed-freespace-adaptive-random-10-95", seed=0, windows=3)
    kwargs = load_profile(None).chain_kwargs()
    assert kwargs["fading"] is not None
    air = [(w, lk) for w in p.windows for lk in w.links if lk.kind == "air"]
    h_air = np.array([max(w.positions[lk.a][2], w.positions[lk.b][2]) for w, lk in air])
    d3d = np.array([lk.distance_m for _, lk in air])
    geom = LinkGeometry(d3d_m=d3d, d2d_m=d3d, h_ground_m=np.zeros(len(air)), h_air_m=h_air,
                        air_to_air=np.zeros(len(air), dtype=bool))
    loss_db = np.array([lk.pathloss_db for _, lk in air])
    want = np.array([lk.loss for _, lk in air])
    same = LinkChain.build(tx_power_dbm=10.0, noise_dbm=-95.0, **kwargs).links(geom, loss_db)
    np.testing.assert_allclose(same.loss, want, atol=LOSS_TOL)
    drifted = LinkChain.build(tx_power_dbm=10.0, noise_dbm=-95.0, **{**kwargs, "fading": None}).links(geom, loss_db)
    assert np.abs(drifted.loss - want).max() > 10 * LOSS_TOL


def test_link_chain_units_and_defaults():
    chain = LinkChain.build(tx_power_dbm=20.0, noise_dbm=-90.0, tx_gain_dbi=1.0, rx_gain_dbi=2.0, modulation="mcs3")
    geom = LinkGeometry.ground_to_air(np.array([100.0, 200.0]), np.array([60.0, 60.0]))
    out = chain.links(geom, np.array([90.0, 100.0]), shadow_db=np.array([1.0, -2.0]))
    np.testing.assert_allclose(out.pathloss_db, [91.0, 98.0])  # total = median + shadowing
    np.testing.assert_allclose(out.snr_db, [20.0 + 3.0 - 91.0 + 90.0, 20.0 + 3.0 - 98.0 + 90.0])
    assert out.mcs.tolist() == [3, 3] and out.k_db is None and len(out) == 2
    # 20 + 3 - PL >= -82 dBm: PL 104 hears, PL 106 does not
    h = chain.hears(3, np.array([[0, 1], [1, 2]]), np.array([104.0, 106.0]))
    assert h[0, 1] and h[1, 0] and not h[1, 2] and not h[0, 2] and h.diagonal().all()
    phy = LinkChain.build(link_layer=chain.link_layer.model_copy(update={"rate_model": "phy"}))
    assert phy.shared_rate_mbps(np.array([[0, 1]]), np.array([400.0]), h) is None
