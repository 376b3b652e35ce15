"""Airtime sharing: links within carrier-sense range of each other share one DCF channel.

All links of a swarm use one 20 MHz channel. 802.11 DCF lets a station transmit only when it
senses the medium idle, so links whose radios hear each other take turns. Rule (per window, over
the active air links):

* Carrier sense (IEEE Std 802.11-2020 17.3.10.6, CCA for the 20 MHz OFDM PHY): a receiver must
  detect the start of a valid OFDM transmission at or above -82 dBm (`CCA_DBM`). Node u hears
  node v when P_tx - PL(u, v) >= -82 dBm, with PL the window's total path loss of the pair
  (median + shadowing, the same number the link's SNR uses; antenna gains added).
* Contention set C(e) of a link e = (a, b): every active air link f = (c, d) with an end that
  hears an end of e (a or b hears c or d, either way), e included. This is a single-hop
  neighbourhood: hidden terminals and spatial reuse beyond it are not modelled.
* Share: DCF gives every backlogged station the same long-run chance to transmit, one frame at
  a time, whatever its rate - the "performance anomaly" of Heusse, Rousseau, Berger-Sabbatel
  and Duda, "Performance anomaly of 802.11b", IEEE INFOCOM 2003: with N contenders each gets one
  frame per cycle of sum_j T_j, so

      rate_e = 8 L / sum_{f in C(e)} E[T_f]                           (L = packet bytes)

  with E[T_f] the expected channel time of a frame on link f (`budget.LinkParams.mac_time_us`,
  retries included). A lone link keeps its own DCF rate 8 L / E[T_e]. Collisions between
  contenders (Bianchi 2000) are not added; the result is the saturation share, an upper bound
  on what each link gets when all carry traffic, which is what the shaper must cap.

The two directions of a link are one contender: the emulated traffic is mostly one-way (HTTP
downloads, with small TCP ACKs back).
"""

from __future__ import annotations

import numpy as np

CCA_DBM = -82.0  # 802.11-2020 17.3.10.6: 20 MHz OFDM preamble detection threshold


def hears_matrix(n_nodes: int, pairs, pathloss_db, tx_power_dbm: float, gains_dbi: float = 0.0,
                 cca_dbm: float = CCA_DBM) -> np.ndarray:
    """(n, n) bool: node u hears node v (symmetric; path loss of the pairs given, others deaf)."""
    p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    rx = tx_power_dbm + gains_dbi - np.asarray(pathloss_db, dtype=float)
    ok = rx >= cca_dbm
    h = np.zeros((n_nodes, n_nodes), dtype=bool)
    h[p[ok, 0], p[ok, 1]] = True
    h[p[ok, 1], p[ok, 0]] = True
    np.fill_diagonal(h, True)
    return h


def contention_sets(links, hears: np.ndarray) -> np.ndarray:
    """(m, m) bool over the links (m, 2): C[e, f] when an end of f hears an end of e."""
    e = np.asarray(links, dtype=np.int64).reshape(-1, 2)
    if e.size == 0:
        return np.zeros((0, 0), dtype=bool)
    h = np.asarray(hears, dtype=bool)
    return h[e[:, 0][:, None], e[:, 0][None, :]] | h[e[:, 0][:, None], e[:, 1][None, :]] | \
        h[e[:, 1][:, None], e[:, 0][None, :]] | h[e[:, 1][:, None], e[:, 1][None, :]]


def shared_rate_mbps(links, mac_time_us, hears: np.ndarray, packet_bytes: int = 1500) -> np.ndarray:
    """Heusse et al.'s share: 8 L / sum of E[T] over each link's contention set (Mbit/s)."""
    t = np.asarray(mac_time_us, dtype=float)
    c = contention_sets(links, hears)
    if c.size == 0:
        return np.zeros(0)
    return 8.0 * packet_bytes / (c.astype(float) @ t)
