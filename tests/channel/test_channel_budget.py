"""Link budget and 802.11 link layer: SNR, airtimes, ARQ residual loss, delay and rate."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.channel.budget import (
    LinkBudget,
    LinkLayer,
    attempt_time_us,
    link_params,
    link_params_from_per,
    mpdu_per,
    ppdu_airtime_us,
)
from uavcas.channel.mcs import MCS_80211AG as T


def test_snr_budget():
    b = LinkBudget(tx_power_dbm=30.0, tx_gain_dbi=2.0, rx_gain_dbi=1.0, noise_dbm=-95.0)
    assert float(b.snr_db(100.0)) == pytest.approx(30 + 3 - 100 + 95)
    assert LinkBudget().noise_dbm == -95.0 and LinkBudget().tx_gain_dbi == 0.0
    np.testing.assert_allclose(LinkBudget(tx_power_dbm=10).snr_db(np.array([80.0, 90.0])), [25.0, 15.0])


def test_ofdm_airtimes():
    # 1536-octet MPDU at 54 Mbit/s: 16 + 4 + 4 * ceil(12310 / 216) = 248 us; at 6 Mbit/s 2072 us.
    assert float(ppdu_airtime_us(8 * 1536, 216)) == 248.0
    assert float(ppdu_airtime_us(8 * 1536, 24)) == 2072.0
    # ACK (14 octets) at 24 Mbit/s (the basic rate used for 54) = 28 us; at 6 Mbit/s = 44 us.
    t = attempt_time_us(np.array([6, 0]), T, LinkLayer(), 0)
    # DIFS 34 + mean backoff 7.5 slots 67.5 + DATA + SIFS 16 + ACK
    np.testing.assert_allclose(t, [34 + 67.5 + 248 + 16 + 28, 34 + 67.5 + 2072 + 16 + 44])
    # Retries double the contention window: attempt 1 waits 15.5 slots on average.
    assert float(attempt_time_us(6, T, LinkLayer(), 1) - attempt_time_us(6, T, LinkLayer(), 0)) == 9 * 8.0


def test_clean_link_rates_follow_dcf_efficiency():
    snr = np.full(7, 60.0)  # error-free at every MCS
    lp = link_params(snr, np.arange(7), np.full(7, 100.0))
    assert np.all(lp.loss < 1e-30)
    # ~30.5 Mbit/s of 1500-byte packets at 54 Mbit/s, ~5.37 at 6 (cf. Jun et al., NCA 2003).
    assert lp.rate_mbps[6] == pytest.approx(12000 / 393.5, rel=1e-9)
    assert lp.rate_mbps[0] == pytest.approx(12000 / 2233.5, rel=1e-9)
    assert np.all(np.diff(lp.rate_mbps) > 0) and np.all(lp.rate_mbps < T.rate_mbps)
    # Lower MCS -> longer airtime -> larger delay.
    assert np.all(np.diff(lp.delay_ms) < 0)
    assert lp.delay_ms[6] == pytest.approx(100 / 299_792_458 * 1e3 + 0.1 + 0.3935, rel=1e-9)


def test_paper_parity_mode_is_raw_per_and_phy_rate():
    link = LinkLayer(retry_limit=0, rate_model="phy", mac_overhead_bytes=0)
    snr, mcs = np.array([8.0, 12.0, 27.0]), np.array([0, 2, 6])
    lp = link_params(snr, mcs, np.zeros(3), link=link)
    raw = 1 - (1 - T.ber(snr, mcs)) ** 12000
    np.testing.assert_allclose(lp.loss, raw, rtol=1e-9)
    np.testing.assert_allclose(lp.rate_mbps, [6, 12, 54])


def test_arq_residual_loss_and_expected_retry_time():
    link = LinkLayer(retry_limit=6)
    p = np.array([0.0, 0.3, 0.9, 1.0])
    mcs = np.zeros(4, int)
    lp = link_params_from_per(p, mcs, np.zeros(4), link=link)
    np.testing.assert_allclose(lp.loss, p**7)
    t = np.array([attempt_time_us(0, T, link, k) for k in range(7)])
    expected_us = np.array([np.sum(pp ** np.arange(7) * t) for pp in p])
    np.testing.assert_allclose(lp.delay_ms, 0.1 + expected_us / 1e3)
    np.testing.assert_allclose(lp.rate_mbps, 12000 / expected_us)
    assert lp.delay_ms[3] > 20 and lp.rate_mbps[3] < 0.6  # 7 failed attempts at 6 Mbit/s
    # More retries: less residual loss, more delay.
    more = link_params_from_per(p, mcs, np.zeros(4), link=LinkLayer(retry_limit=10))
    assert np.all(more.loss[1:3] < lp.loss[1:3]) and np.all(more.delay_ms[1:] > lp.delay_ms[1:])


def test_mpdu_per_uses_mpdu_length_and_loss_grows_as_snr_falls():
    snr = np.linspace(2.0, 14.0, 25)
    p = mpdu_per(snr, np.zeros(25, int))
    assert np.all(np.diff(p) <= 0)
    loss = link_params(snr, np.zeros(25, int), np.zeros(25)).loss
    assert np.all(np.diff(loss) <= 0) and loss[0] > 0.99 and loss[-1] < 1e-12
    short = mpdu_per(6.0, 0, link=LinkLayer(packet_bytes=100))
    assert short < mpdu_per(6.0, 0)


def test_link_layer_validation():
    with pytest.raises(ValueError):
        LinkLayer(retry_limit=-1)
    with pytest.raises(ValueError):
        LinkLayer(rate_model="shannon")
