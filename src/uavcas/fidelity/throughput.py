"""Throughput of a saturated link direction against its planned rate.

A bin (`Tolerances.saturated_bin_s`) is saturated when the FIFO model's queue never emptied over
all of it (`fifo.busy_intervals`): the port should have sent at exactly its planned rate. What it
delivered in the bin is counted with **each frame spread over its serialisation time** at the
rate in force (a frame seen at the next switch at t occupied the link over [t, t + 8 L / R)):
counting whole frames by the bin they were seen in makes the ratio jump by one frame per bin,
which on a slow link is most of it (0.27 Mbit/s, 200 ms bins: 4 or 5 whole 45 ms frames, a
ratio of 0.91 or 1.14 for a port sending at exactly its rate). The ratio is measured / planned.
"""

from __future__ import annotations

import numpy as np

from . import fifo
from .inforce import PortShaping


def delivered_bits(t_out: np.ndarray, bits: np.ndarray, rate_bps: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Bits delivered by each time in `at`, frame k spread evenly over [t_out[k], t_out[k] + bits[k] / rate_bps[k]).

    sum_k bits_k * clip((t - t_k) / s_k, 0, 1) = sum over started frames of R_k (t - t_k) minus
    sum over finished frames of R_k (t - e_k), e_k = t_k + s_k: four cumulative sums. Times
    should be relative to a nearby origin (the products lose precision on Unix seconds).
    """
    end = t_out + bits / rate_bps

    def started(t0: np.ndarray) -> np.ndarray:
        o = np.argsort(t0, kind="stable")
        k = np.searchsorted(t0[o], at, side="right")
        r = np.concatenate([[0.0], np.cumsum(rate_bps[o])])
        rt = np.concatenate([[0.0], np.cumsum(rate_bps[o] * t0[o])])
        return at * r[k] - rt[k]

    return started(t_out) - started(end)


def saturated_ratios(ready: np.ndarray, start: np.ndarray, t_out: np.ndarray, length_b: np.ndarray,
                     shaping: PortShaping, t0: float, bin_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Saturated bins of one port: (bin start times, measured / planned rate, setting index).

    `ready`, `start`: the model's frames (`fifo.serve`); `t_out`, `length_b`: when the same
    frames were seen at the next switch and their lengths. Bins start at t0 + k * bin_s; only
    bins under one setting of the port count (the rate it was serving at)."""
    e = np.zeros(0)
    busy = fifo.busy_intervals(ready, start)
    if busy.shape[0] == 0:
        return e, e, e.astype(np.int64)
    k0 = np.ceil((busy[:, 0] - t0) / bin_s).astype(np.int64)
    k1 = np.floor((busy[:, 1] - t0) / bin_s).astype(np.int64)
    bins = np.concatenate([np.arange(a, b) for a, b in zip(k0, k1) if b > a] or [np.zeros(0, np.int64)])
    if bins.shape[0] == 0:
        return e, e, e.astype(np.int64)
    t_bin = t0 + bins * bin_s
    s_a, s_b = shaping.at(t_bin), shaping.at(t_bin + bin_s)
    keep = (s_a == s_b) & (s_a >= 0)
    t_bin, bins, s = t_bin[keep], bins[keep], s_a[keep]
    k_out = shaping.at(t_out)
    rate = shaping.rate_mbps[np.maximum(k_out, 0)] * 1e6
    bits = delivered_bits(t_out - t0, length_b * 8.0, rate, np.concatenate([bins * bin_s, (bins + 1) * bin_s]))
    got = (bits[bins.shape[0]:] - bits[:bins.shape[0]]) / bin_s
    return t_bin, got / (shaping.rate_mbps[s] * 1e6), s
