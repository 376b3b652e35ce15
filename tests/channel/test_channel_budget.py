"""Link budget and 802.11 link layer: SNR, airtimes, coded PER, ARQ residual loss, delay, rate, MCS choice."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.channel.budget import (
    LinkBudget,
    LinkLayer,
    attempt_time_us,
    link_chain,
    link_params,
    link_params_from_per,
    ppdu_airtime_us,
)
from uavcas.channel.frames import mpdu_per as _mpdu_per
from uavcas.channel.frames import tabulated_per as _tabulated_per
from uavcas.channel.mcs import MCS_80211AG as T


def mpdu_per(snr, mcs, link=LinkLayer()):
    return _mpdu_per(snr, mcs, T, link)


def tabulated_per(snr, mcs, link=LinkLayer()):
    return _tabulated_per(snr, mcs, T, link)


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
    # The MAC time is in the rate (E[T] = 8 L / rate), NOT in the delay: propagation + processing only.
    np.testing.assert_allclose(lp.mac_time_us, 12000 / lp.rate_mbps)
    np.testing.assert_allclose(lp.delay_ms, 100 / 299_792_458 * 1e3 + 0.1)


def test_paper_parity_mode_is_raw_per_and_phy_rate():
    link = LinkLayer(retry_limit=0, rate_model="phy", mac_overhead_bytes=0, coding="uncoded",
                     implementation_loss_db=0.0)
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
    np.testing.assert_allclose(lp.mac_time_us, expected_us)
    np.testing.assert_allclose(lp.delay_ms, 0.1)
    np.testing.assert_allclose(lp.rate_mbps, 12000 / expected_us)
    assert lp.mac_time_us[3] > 20_000 and lp.rate_mbps[3] < 0.6  # 7 failed attempts at 6 Mbit/s
    # More retries: less residual loss, more channel time.
    more = link_params_from_per(p, mcs, np.zeros(4), link=LinkLayer(retry_limit=10))
    assert np.all(more.loss[1:3] < lp.loss[1:3]) and np.all(more.mac_time_us[1:] > lp.mac_time_us[1:])


def test_mpdu_per_uses_mpdu_length_and_loss_grows_as_snr_falls():
    snr = np.linspace(2.0, 16.0, 29)
    p = mpdu_per(snr, np.zeros(29, int))
    assert np.all(np.diff(p) <= 0)
    loss = link_params(snr, np.zeros(29, int), np.zeros(29)).loss
    assert np.all(np.diff(loss) <= 0) and loss[0] > 0.99 and loss[-1] < 1e-12
    short = mpdu_per(9.0, 0, link=LinkLayer(packet_bytes=100))
    assert short < mpdu_per(9.0, 0)


def test_coded_per_counts_the_code_rate_and_the_implementation_loss():
    link = LinkLayer(packet_bytes=1000, mac_overhead_bytes=0, implementation_loss_db=0.0)
    snr = np.arange(0.0, 30.0, 0.01)

    def per10(m):  # SNR where the PER of 1000-octet frames falls below 10 %
        return snr[np.argmax(mpdu_per(snr, np.full(snr.shape, m), link=link) < 0.1)]

    at = [per10(m) for m in range(7)]
    assert np.all(np.diff(at) > 0)
    # Same constellation, rate 3/4 needs ~2.9 dB more than rate 1/2 (BPSK and QPSK, and 16-QAM ~3.1 dB).
    assert at[1] - at[0] == pytest.approx(2.9, abs=0.15) and at[3] - at[2] == pytest.approx(2.9, abs=0.15)
    assert at[5] - at[4] == pytest.approx(3.1, abs=0.2)
    # The 802.11 thresholds sit 3-5 dB above these AWGN points: the 5 dB implementation margin.
    gap = T.snr_threshold_db - np.array(at)
    assert np.all((gap > 3.0) & (gap < 5.5))
    # The default link layer applies that 5 dB before the bound.
    np.testing.assert_allclose(mpdu_per(snr[::100] + 5.0, 0,
                                        link=link.model_copy(update={"implementation_loss_db": 5.0})),
                               mpdu_per(snr[::100], 0, link=link))


def test_tabulated_per_matches_the_exact_bound():
    rng = np.random.default_rng(3)
    snr, mcs = rng.uniform(-5.0, 45.0, 20000), rng.integers(0, 7, 20000)
    exact, table = mpdu_per(snr, mcs), tabulated_per(snr, mcs)
    ok = exact > 1e-12
    assert np.max(np.abs(table[ok] / exact[ok] - 1.0)) < 1e-4
    assert np.max(np.abs(table - exact)) < 2e-5


def test_link_chain_selects_by_goodput_or_by_threshold():
    snr = np.arange(0.0, 40.0, 0.5)
    mcs_t, _, lp_t = link_chain(snr, np.zeros(snr.size), selection="threshold")
    np.testing.assert_array_equal(mcs_t, T.select(snr, 3.0))
    mcs_g, reach_g, lp_g = link_chain(snr, np.zeros(snr.size), k_db=np.full(snr.size, 5.5))

    def minstrel(reach, m):  # success ratio over the attempts at the chosen level x bits per time
        return (1 - reach[:, 4]) / reach[:, :4].sum(axis=1) / attempt_time_us(m, T, LinkLayer(), 0)

    best = minstrel(reach_g, mcs_g)
    for m in range(7):
        _, reach, _ = link_chain(snr, np.zeros(snr.size), k_db=np.full(snr.size, 5.5), fixed_mcs=m)
        assert np.all(best >= minstrel(reach, m) - 1e-15)
    assert np.all(np.diff(mcs_g) >= 0) and mcs_g[0] == 0 and mcs_g[-1] == 6
    # The retry chain ends at the base rate: far less residual loss than retrying at the chosen level.
    k = np.full(snr.size, 5.5)
    for m in (3, 6):
        _, _, fb = link_chain(snr, np.zeros(snr.size), k_db=k, fixed_mcs=m)
        _, _, same = link_chain(snr, np.zeros(snr.size), link=LinkLayer(fallback_after=None), k_db=k, fixed_mcs=m)
        assert np.all(fb.loss <= same.loss + 1e-12) and np.all(fb.loss[snr > 20] < 0.5 * same.loss[snr > 20])
    assert lp_g.loss[snr > 20].max() < 0.02 and lp_g.loss[-1] < 2e-4
    assert np.all(np.diff(lp_g.loss[snr > 10]) < 0)  # only the deep fades below MCS0 remain
    fixed, _, _ = link_chain(snr, np.zeros(snr.size), fixed_mcs=4)
    assert np.all(fixed == 4)


def test_link_layer_validation():
    with pytest.raises(ValueError):
        LinkLayer(retry_limit=-1)
    with pytest.raises(ValueError):
        LinkLayer(rate_model="shannon")
