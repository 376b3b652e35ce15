"""MCS table, thresholds, selection, BER and PER against known values."""

from __future__ import annotations

from importlib import resources

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.special import erfc

from uavcas.channel.mcs import MCS_80211AG, McsTable, ber, parse_modulation, per, reference_noise_dbm

T = MCS_80211AG


def test_table_is_the_papers_seven_levels():
    assert len(T) == 7
    assert T.modulation == ("BPSK", "BPSK", "QPSK", "QPSK", "16-QAM", "16-QAM", "64-QAM")
    assert T.rate_mbps.tolist() == [6, 9, 12, 18, 24, 36, 54]
    assert T.code_rate.tolist() == [0.5, 0.75, 0.5, 0.75, 0.5, 0.75, 0.75]
    assert T.sensitivity_dbm.tolist() == [-82, -81, -79, -77, -74, -70, -65]
    # PHY rate = N_DBPS / 4 us symbol.
    np.testing.assert_allclose(T.n_dbps / 4.0, T.rate_mbps)
    # The data file names its source.
    text = resources.files("uavcas.channel").joinpath("data", "mcs_80211ag.csv").read_text()
    assert "IEEE Std 802.11-2020" in text and "Table 17-18" in text


def test_thresholds_from_sensitivity_and_reference_noise():
    assert reference_noise_dbm() == pytest.approx(-90.99, abs=0.01)
    np.testing.assert_allclose(T.snr_threshold_db, [8.99, 9.99, 11.99, 13.99, 16.99, 20.99, 25.99], atol=0.01)
    custom = McsTable.load(noise_ref_dbm=-95.0)
    np.testing.assert_allclose(custom.snr_threshold_db, T.sensitivity_dbm + 95.0)


def test_adaptive_selection_uses_the_margin():
    thr = T.snr_threshold_db
    # Exactly threshold + 3 dB selects that level; a hair below drops one level.
    for k in range(1, 7):
        assert T.select(np.array([thr[k] + 3.0]))[0] == k
        assert T.select(np.array([thr[k] + 3.0 - 1e-6]))[0] == k - 1
    # Meeting the bare threshold is not enough with a 3 dB margin ...
    assert T.select(np.array([thr[6] + 1.0]))[0] == 5
    # ... but is with margin 0.
    assert T.select(np.array([thr[6] + 1.0]), margin_db=0.0)[0] == 6
    # Below MCS0's threshold + margin the link stays at MCS0.
    assert T.select(np.array([-20.0, 0.0, 11.0])).tolist() == [0, 0, 0]
    assert T.select(np.array([100.0]))[0] == 6


@given(st.lists(st.floats(-30, 60), min_size=2, max_size=30))
def test_selection_is_monotone_in_snr(snrs):
    s = np.sort(np.array(snrs))
    assert np.all(np.diff(T.select(s)) >= 0)


def test_fixed_modulation():
    snr = np.array([0.0, 40.0])
    assert T.choose(snr, 3).tolist() == [3, 3]
    assert T.choose(snr, "mcs6").tolist() == [6, 6]
    assert T.choose(snr, "adaptive").tolist() == [0, 6]
    assert parse_modulation("adaptive") is None and parse_modulation("mcs2") == 2
    for bad in ("mcs7", -1, "fast", "mcs"):
        with pytest.raises(ValueError):
            parse_modulation(bad)


def test_ber_known_values():
    # BPSK at Eb/N0 = 9.6 dB: the textbook 1e-5 point (Q(4.265) = 9.74e-6).
    assert float(ber(9.6, 2)) == pytest.approx(9.74e-6, rel=0.01)
    # QPSK per bit equals BPSK at the same Eb/N0 (Es = 2 Eb).
    assert float(ber(9.6 + 10 * np.log10(2), 4)) == pytest.approx(float(ber(9.6, 2)), rel=1e-9)
    # BPSK at Eb/N0 = 0 dB: Q(sqrt 2) = 0.0786.
    assert float(ber(0.0, 2)) == pytest.approx(0.07865, abs=1e-4)
    # 16-QAM at Eb/N0 = 10 dB (Es/N0 = 16.02 dB): 3/4 Q(sqrt(Es/N0 / 5)) = 1.754e-3.
    assert float(ber(10 + 10 * np.log10(4), 16)) == pytest.approx(1.754e-3, rel=0.005)
    # Vectorised over mixed orders, capped at 0.5.
    out = ber(np.array([-50.0, 20.0, 20.0]), np.array([2, 16, 64]))
    assert out[0] <= 0.5 and out[1] < out[2]
    with pytest.raises(ValueError):
        ber(10.0, 8)


def _exact_square_qam_ber(esn0_db: float, m: int) -> float:
    """Exact Gray BER of square M-QAM for M = 16 (Cho & Yoon, IEEE Trans. Commun. 2002)."""
    g = 10 ** (esn0_db / 10)
    q = lambda x: 0.5 * erfc(x / np.sqrt(2))  # noqa: E731
    a = np.sqrt(3 * g / (m - 1))
    assert m == 16
    return 0.75 * q(a) + 0.5 * q(3 * a) - 0.25 * q(5 * a)


@pytest.mark.parametrize("esn0_db", [14.0, 18.0, 20.0])
def test_qam16_matches_exact_gray_ber(esn0_db):
    # Proakis' expression is the nearest-neighbour approximation; within 1 % where it matters.
    assert float(ber(esn0_db, 16)) == pytest.approx(_exact_square_qam_ber(esn0_db, 16), rel=0.01)


def test_qam64_against_monte_carlo():
    # Gray-coded 64-QAM (8-PAM per axis) through AWGN at Es/N0 = 22 dB.
    rng = np.random.default_rng(1)
    n_sym, esn0 = 400_000, 10 ** (22 / 10)
    gray = np.array([0, 1, 3, 2, 6, 7, 5, 4])  # level index -> 3-bit Gray label
    levels = np.arange(-7, 8, 2, dtype=float)
    es = 2 * np.mean(levels**2)  # energy per 2-D symbol
    idx = rng.integers(0, 8, (n_sym, 2))
    rx = levels[idx] + rng.normal(0, np.sqrt(es / esn0 / 2), (n_sym, 2))
    det = np.clip(np.round((rx + 7) / 2), 0, 7).astype(int)
    diff = gray[idx] ^ gray[det]
    bit_errors = sum(((diff >> b) & 1).sum() for b in range(3))
    sim = bit_errors / (n_sym * 6)
    assert float(ber(22.0, 64)) == pytest.approx(sim, rel=0.1)


def test_per():
    assert float(per(0.0, 12000)) == 0.0
    assert float(per(1e-5, 12000)) == pytest.approx(1 - (1 - 1e-5) ** 12000, rel=1e-12)
    assert float(per(1e-12, 12000)) == pytest.approx(1.2e-8, rel=1e-6)  # no cancellation
    assert float(per(0.5, 12000)) == 1.0
    assert float(per(1e-4, 8 * 1500)) > float(per(1e-4, 8 * 100))
