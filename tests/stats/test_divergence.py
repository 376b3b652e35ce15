"""Properties of the bounded divergences: bounds, symmetry, identity, unit invariance."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from uavcas.stats.divergence import (
    compare_pairwise,
    compare_pooled,
    flow_counts,
    hellinger,
    histogram,
    jsd,
    log_bins,
)

# IATs: exact zeros or 1 ns .. 3 h (no subnormals: scaling them by 2**k would underflow to 0)
iat = st.one_of(st.just(0.0), st.floats(min_value=1e-9, max_value=1e4, allow_nan=False))
samples = arrays(np.float64, st.integers(1, 60), elements=iat)
hists = arrays(np.float64, 8, elements=st.floats(0, 1e3, allow_nan=False)).filter(lambda a: a.sum() > 1e-9)


@settings(max_examples=150, deadline=None)
@given(hists, hists)
def test_bounds_and_symmetry(p, q):
    for f in (hellinger, jsd):
        v = f(p, q)
        assert 0.0 <= v <= 1.0
        assert v == pytest.approx(f(q, p), abs=1e-12)


@settings(max_examples=100, deadline=None)
@given(hists)
def test_zero_on_identical(p):
    assert hellinger(p, p) == pytest.approx(0.0, abs=1e-7)
    assert jsd(p, p) == pytest.approx(0.0, abs=1e-12)


def test_disjoint_supports_reach_one():
    p, q = np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    assert hellinger(p, q) == pytest.approx(1.0)
    assert jsd(p, q) == pytest.approx(1.0)


@settings(max_examples=100, deadline=None)
@given(samples, samples, st.integers(-20, 20))
def test_unit_invariance_data_and_bins_scaled_together(a, b, k):
    c = 2.0**k  # exact in floating point, so no value crosses an edge by rounding
    edges = log_bins([a, b], 20)
    ha, hb = histogram(a, edges), histogram(b, edges)
    sa, sb = histogram(a * c, edges * c), histogram(b * c, edges * c)
    assert hellinger(sa, sb) == pytest.approx(hellinger(ha, hb), abs=1e-12)
    assert jsd(sa, sb) == pytest.approx(jsd(ha, hb), abs=1e-12)


def test_unit_change_seconds_to_ms_with_automatic_bins():
    rng = np.random.default_rng(0)
    a, b = rng.lognormal(0, 1, 3000), rng.lognormal(0.3, 1, 3000)
    e_s, e_ms = log_bins([a, b]), log_bins([a * 1e3, b * 1e3])
    assert np.allclose(e_ms, e_s * 1e3)
    assert jsd(histogram(a, e_s), histogram(b, e_s)) == pytest.approx(
        jsd(histogram(a * 1e3, e_ms), histogram(b * 1e3, e_ms)), abs=1e-3)


@settings(max_examples=80, deadline=None)
@given(samples, samples)
def test_bins_cover_all_data_zero_bin_first(a, b):
    edges = log_bins([a, b], 10)
    assert edges[0] == 0.0 and np.all(np.diff(edges) > 0)
    h = histogram(np.concatenate([a, b]), edges)
    assert h.sum() == pytest.approx(1.0)
    if (np.concatenate([a, b]) == 0).any():
        assert h[0] > 0  # zero IATs are kept, in the zero bin


def test_out_of_range_values_are_an_error_not_dropped():
    edges = log_bins([np.array([1.0, 2.0])], 4)
    with pytest.raises(ValueError, match="outside the bins"):
        histogram(np.array([3.0]), edges)
    with pytest.raises(ValueError, match=">= 0"):
        log_bins([np.array([-1.0])])


def test_bootstrap_ci_brackets_and_is_seeded():
    rng = np.random.default_rng(1)
    fa = [rng.exponential(1.0, 30) for _ in range(40)]
    fb = [rng.exponential(1.5, 30) for _ in range(40)]
    edges = log_bins(fa + fb, 30)
    ca, cb = flow_counts(fa, edges), flow_counts(fb, edges)
    r1, r2 = compare_pooled(ca, cb, n_boot=50, seed=7), compare_pooled(ca, cb, n_boot=50, seed=7)
    assert r1 == r2
    assert 0 <= r1.hellinger_lo <= r1.hellinger_hi <= 1 and 0 <= r1.jsd_lo <= r1.jsd_hi <= 1
    h, j = compare_pairwise(ca, cb, n_pairs=200, seed=0)
    assert 0 <= h <= 1 and 0 <= j <= 1
