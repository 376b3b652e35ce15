"""The authors' legacy metric is unbounded (far above 1 for fast floods); ours stays in [0, 1]."""

from __future__ import annotations

import numpy as np

from uavcas.analysis.legacy import legacy_divergence
from uavcas.stats.divergence import compare_pooled, flow_counts, log_bins


def _flows(rng, mean_iat, n_flows, n_pkts):
    return [rng.exponential(mean_iat, n_pkts - 1) for _ in range(n_flows)]


def test_legacy_far_above_one_for_fast_floods_bounded_metrics_in_unit_interval():
    rng = np.random.default_rng(0)
    benign = [rng.lognormal(np.log(1.6), 0.6, 150) for _ in range(60)]
    flood = _flows(rng, 1e-3, 60, 400)  # ~1,000 pps SYN flood
    leg = legacy_divergence(flood, benign, seed=0)
    assert leg.hellinger > 10 and leg.n_pairs == 60 * 60
    edges = log_bins(flood + benign)
    c = compare_pooled(flow_counts(flood, edges), flow_counts(benign, edges), n_boot=20)
    assert 0.99 <= c.hellinger <= 1.0 and 0.99 <= c.jsd <= 1.0


def test_legacy_rules_min_packets_and_pairs():
    rng = np.random.default_rng(1)
    short = _flows(rng, 1.0, 10, 50)  # < 100 packets: not eligible
    assert legacy_divergence(short, short).n_pairs == 0
    many = _flows(rng, 1.0, 250, 120)
    assert legacy_divergence(many, many).n_pairs == 200 * 200
