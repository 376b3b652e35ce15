"""Airtime sharing among links in carrier-sense range (Heusse et al. 2003), hand-computed."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.channel import CCA_DBM, hears_matrix, shared_rate_mbps
from uavcas.channel.airtime import contention_sets


def test_hears_uses_the_cca_threshold():
    pairs = np.array([[0, 1], [1, 2], [0, 2]])
    # 20 dBm: 0-1 at 101 dB -> -81 dBm (heard), 1-2 at 102.5 dB -> -82.5 (not), 0-2 at 80 dB (heard).
    h = hears_matrix(3, pairs, [101.0, 102.5, 80.0], 20.0)
    assert CCA_DBM == -82.0
    assert h[0, 1] and h[1, 0] and h[0, 2] and not h[1, 2] and np.all(np.diag(h))
    assert hears_matrix(3, pairs, [101.0, 102.5, 80.0], 20.0, gains_dbi=1.0)[1, 2]


def test_shares_are_hand_computed():
    # Nodes 0..5; links a = (0, 1), b = (2, 3), c = (4, 5). 1 hears 2; nobody hears 4 or 5.
    hears = np.eye(6, dtype=bool)
    hears[1, 2] = hears[2, 1] = True
    links = np.array([[0, 1], [2, 3], [4, 5]])
    t = np.array([400.0, 2200.0, 1000.0])  # E[T] per packet, us
    c = contention_sets(links, hears)
    assert c.tolist() == [[True, True, False], [True, True, False], [False, False, True]]
    rate = shared_rate_mbps(links, t, hears)
    # a and b alternate one frame each: 12000 bit / (400 + 2200) us = 4.615 Mbit/s for both
    # (the slow link drags the fast one down: Heusse's anomaly); c keeps 12000 / 1000 = 12.
    np.testing.assert_allclose(rate, [4.6153846, 4.6153846, 12.0])


def test_n_links_in_one_domain_get_one_nth():
    n = 20
    links = np.c_[np.arange(0, 2 * n, 2), np.arange(1, 2 * n, 2)]
    hears = np.ones((2 * n, 2 * n), dtype=bool)
    rate = shared_rate_mbps(links, np.full(n, 393.5), hears)
    assert rate == pytest.approx(np.full(n, 12000 / 393.5 / n))
