"""Rician fading: K(h) spec vectors, the quantile quadrature against closed forms and Monte Carlo."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import ncx2

from uavcas.channel import TR36777_UMA_AV_K, KFactorProfile
from uavcas.channel.budget import link_params
from uavcas.channel.frames import mpdu_per as _mpdu_per
from uavcas.channel.linklayer import LinkLayer
from uavcas.channel.mcs import MCS_80211AG as T


def mpdu_per(snr, mcs, link=LinkLayer()):
    return _mpdu_per(snr, mcs, T, link)
from uavcas.channel.fading import expect, fading_nodes, tr36777_uma_av_k_db


def test_tr36777_k_factor_spec_vectors():
    # TR 36.777 Table B.1.2-2, UMa-AV LOS: 4.217 log10(h) + 5.787 dB.
    assert float(tr36777_uma_av_k_db(30.0)) == pytest.approx(12.016, abs=1e-3)
    assert float(tr36777_uma_av_k_db(110.0)) == pytest.approx(14.396, abs=1e-3)
    assert float(tr36777_uma_av_k_db(10.0)) == float(tr36777_uma_av_k_db(22.5))  # clamped to the table's range
    np.testing.assert_allclose(TR36777_UMA_AV_K.at([30.0, 110.0]), [12.016, 14.396], atol=1e-3)


def test_k_table_interpolates_and_validates():
    k = KFactorProfile(name="t", altitude_m=(30.0, 110.0), k_db=(5.0, 7.0))
    np.testing.assert_allclose(k.at([10.0, 70.0, 500.0]), [5.0, 6.0, 7.0])
    with pytest.raises(ValueError):
        KFactorProfile(name="t", altitude_m=(30.0,), k_db=())


@pytest.mark.parametrize("k_db", [-10.0, 0.0, 5.5, 12.0, 25.0])
def test_quadrature_moments_are_the_rician_ones(k_db):
    k = 10 ** (k_db / 10)
    gain, w = fading_nodes([k_db])
    g = 10 ** (gain / 10)
    assert float(w.sum()) == pytest.approx(1.0, abs=1e-12)
    assert float((w * g).sum()) == pytest.approx(1.0, abs=1e-9)  # E g = 1
    # E g^2 of the normalised Rician power = (K^2 + 4K + 2) / (K + 1)^2.
    assert float((w * g * g).sum()) == pytest.approx((k * k + 4 * k + 2) / (k + 1) ** 2, rel=2e-3)


def test_window_loss_matches_monte_carlo():
    rng = np.random.default_rng(0)
    k_db, snr = 5.5, np.array([9.0, 13.0, 18.0])
    k = 10 ** (k_db / 10)
    g = ncx2.rvs(2, 2 * k, size=400_000, random_state=rng) / (2 * (k + 1))
    # Residual loss with retries in one fading state: E[PER(SNR g)^7].
    mc = [np.mean(mpdu_per(s + 10 * np.log10(g), 0) ** 7) for s in snr]
    lp = link_params(snr, np.zeros(3, int), np.zeros(3), k_db=np.full(3, k_db))
    np.testing.assert_allclose(lp.loss, mc, rtol=0.03)  # MC standard error ~1 %
    # No fading in the limit of a huge K.
    np.testing.assert_allclose(expect(lambda s: s, np.array([10.0]), 40.0), [10.0], atol=0.02)
