"""Frame errors of 802.11 transmission attempts: PER per attempt, and the probability that each
attempt of the retry chain happens, averaged over the window's fading.

PER per attempt (`mpdu_per`): the coded PER of `uavcas.channel.mcs` (802.11 BCC, union bound)
at SNR minus the link layer's implementation loss, over the whole MPDU (the FCS covers it);
`coding="uncoded"` keeps the paper's uncoded BER. `tabulated_per` is the same from a 0.005 dB
table (the fading quadrature evaluates hundreds of SNRs per link).

Retry chain (`attempt_reach`). Attempt k (k = 0..R, R = retry_limit) is sent at level c_k: the
chosen level for the first `fallback_after` attempts, then the lowest level (6 Mbit/s) - the
last stage of the multi-rate retry chain of 802.11 rate control (Linux mac80211 Minstrel: best
throughput, second best, best probability, then the base rate; here the first three collapse
into the chosen level). `fallback_after=None` keeps the chosen level for every attempt.
Retransmissions of one packet come within the channel's coherence time (a few ms), so they see
the same fading gain g: attempt k happens with probability

    reach_k = E_g[ prod_{j<k} p_{c_j}(SNR g) ]           (reach_0 = 1; reach_{R+1} = loss)

over the Rician distribution of `uavcas.channel.fading` (no fading: g = 1).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .fading import fading_nodes
from .linklayer import LinkLayer
from .mcs import McsTable, per

_PER_GRID_DB = (-40.0, 80.0, 0.005)  # SNR span and step of the tabulated PER


def mpdu_per(snr_db, mcs, table: McsTable, link: LinkLayer) -> np.ndarray:
    """Per-attempt error rate of the MPDU: 1 - (1 - BER)^L with L = link.mpdu_bits, BER coded
    (or not, `link.coding`) at SNR - link.implementation_loss_db."""
    eff = np.asarray(snr_db, dtype=float) - link.implementation_loss_db
    m = np.asarray(mcs, dtype=np.int64)
    b = table.coded_ber(eff, m) if link.coding == "bcc" else table.ber(eff, m)
    return per(b, link.mpdu_bits)


@lru_cache(maxsize=32)
def _log_per_table(table: McsTable, link: LinkLayer) -> np.ndarray:
    """ln PER of every level on the SNR grid (levels x grid), floored at ln 1e-300."""
    lo, hi, step = _PER_GRID_DB
    grid = np.linspace(lo, hi, int(round((hi - lo) / step)) + 1)
    rows = [mpdu_per(grid, np.full(grid.shape, m), table, link) for m in range(len(table))]
    out = np.log(np.maximum(np.array(rows), 1e-300))
    out.setflags(write=False)
    return out


def tabulated_per(snr_db, mcs, table: McsTable, link: LinkLayer) -> np.ndarray:
    """`mpdu_per` interpolated in ln PER on a 0.005 dB grid (relative error < 1e-4 where
    PER > 1e-12). SNRs outside -40..80 dB are clamped to the table."""
    lo, hi, step = _PER_GRID_DB
    logp = _log_per_table(table, link)
    x = (np.clip(np.asarray(snr_db, dtype=float), lo, hi) - lo) / step
    i = np.minimum(x.astype(np.int64), logp.shape[1] - 2)
    f = x - i
    m = np.broadcast_to(np.asarray(mcs, dtype=np.int64), x.shape)
    return np.exp((1.0 - f) * logp[m, i] + f * logp[m, i + 1])


def attempt_levels(mcs, link: LinkLayer) -> np.ndarray:
    """Level of each attempt (k, R + 1): the chosen one, then the lowest after `fallback_after`."""
    m = np.atleast_1d(np.asarray(mcs, dtype=np.int64))
    out = np.repeat(m[:, None], link.retry_limit + 1, axis=1)
    if link.fallback_after is not None:
        out[:, link.fallback_after :] = 0
    return out


def attempt_reach(snr_db, mcs, table: McsTable, link: LinkLayer, k_db=None) -> np.ndarray:
    """reach_k for k = 0..R + 1 per link (shape (k, R + 2)), over fading when `k_db` is given."""
    snr = np.atleast_1d(np.asarray(snr_db, dtype=float))
    levels = attempt_levels(np.broadcast_to(np.asarray(mcs, dtype=np.int64), snr.shape), link)
    n_att = levels.shape[1]
    if k_db is None:
        p = np.stack([mpdu_per(snr, levels[:, j], table, link) for j in range(n_att)], axis=1)
        return np.c_[np.ones(snr.size), np.cumprod(p, axis=1)]
    gain, weight = fading_nodes(np.broadcast_to(np.asarray(k_db, dtype=float), snr.shape))
    inst = snr[:, None] + gain
    out = np.empty((snr.size, n_att + 1))
    out[:, 0] = 1.0
    cache: dict[int, np.ndarray] = {}
    prod = np.ones_like(inst)
    for j in range(n_att):
        col = levels[:, j]
        key = int(col[0]) if np.all(col == col[0]) else -1
        if key < 0 or key not in cache:
            pj = tabulated_per(inst, col[:, None], table, link)
            if key >= 0:
                cache[key] = pj
        else:
            pj = cache[key]
        prod = prod * pj
        out[:, j + 1] = np.sum(weight * prod, axis=1)
    return out


