"""Bounded divergences on shared bins and the error metrics."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.calibration.metrics import (
    KL_SKEW,
    error_metrics,
    hellinger_on_shared_bins,
    jsd_on_shared_bins,
    shared_edges,
    spatial_kl_bits,
)


def test_error_metrics_known_values():
    m = error_metrics([1.0, 2.0, 3.0, 6.0], [0.0, 2.0, 2.0, 4.0])
    assert m["bias_db"] == pytest.approx(1.0)
    assert m["mae_db"] == pytest.approx(1.0)
    assert m["median_ae_db"] == pytest.approx(1.0)
    assert m["rmse_db"] == pytest.approx(np.sqrt(6 / 4))
    assert 0.9 < m["r"] <= 1.0


def test_shared_edges_cover_every_value():
    rng = np.random.default_rng(0)
    a, b = rng.normal(-70, 8, 1000), rng.normal(-50, 3, 10)
    e = shared_edges([a, b], 1.0)
    assert e[0] <= min(a.min(), b.min()) and e[-1] > max(a.max(), b.max())
    h, _ = np.histogram(np.r_[a, b], bins=e)
    assert h.sum() == a.size + b.size


def test_divergences_bounded_and_zero_on_identical():
    rng = np.random.default_rng(1)
    a = rng.normal(0, 1, 5000)
    assert jsd_on_shared_bins(a, a, 0.1)[0] == pytest.approx(0.0, abs=1e-12)
    assert jsd_on_shared_bins(a, a + 100, 0.1)[0] == pytest.approx(1.0)
    e = shared_edges([a, a + 100], 0.5)
    assert hellinger_on_shared_bins(a, a + 100, e) == pytest.approx(1.0)
    assert hellinger_on_shared_bins(a, a, e) == pytest.approx(0.0, abs=1e-12)


def test_spatial_kl_zero_on_identical_and_bounded_by_skew():
    rng = np.random.default_rng(2)
    xy = rng.uniform(0, 100, (2000, 2))
    assert spatial_kl_bits(xy, xy, 10.0) == pytest.approx(0.0, abs=1e-12)
    far = spatial_kl_bits(xy, xy + 1000.0, 10.0)
    assert far == pytest.approx(np.log2(1 / KL_SKEW), rel=1e-6)
