"""Interference from a transmitter outside the swarm (a jammer): its power at each receiver, the
SINR it leaves, and the link parameters under it, through the links' own chain.

Received power (dBm) of an emitter with EIRP P_e (its antenna gain included) at a receiver with
gain G_rx, over the run's path-loss model on the emitter -> receiver geometry:

    I = P_e + G_rx - PL_median(emitter, receiver)

* PL is the same model object the links use (`Channel.model`: log-distance with its carrier
  anchor, TR 36.777, two-ray, free space), so the emitter is on the swarm's own carrier, the
  channel profile's fc. The emitter is placed in the geometry like a node (`LinkGeometry`): a
  ground emitter is the ground end of its path (as a BS is), an airborne one a UAV end.
* Median loss: no shadowing, and for the 3GPP models the LOS-probability-weighted mean (what
  `evaluate` gives without a LOS draw). The swarm's shadowing and LOS processes are per node
  pair (`shadowing.GudmundsonShadowing`); the emitter is no node, and a process of its own
  would re-seed every plan's streams. The median is the mean-field choice.
* Fading: the interferer enters with its mean power (the Rician gain is normalised to unit mean
  power), while the link's own signal keeps the window's fading through `attempt_reach`, as for
  any link: the chain averages the PER over the wanted signal's fading at the SINR.

SINR: noise and interference add in linear power (mW),

    SINR = S - 10 log10(10^(N/10) + 10^(I/10)),   S = SNR + N

and everything after it is the links' chain: MCS (adaptive by Minstrel's criterion or the
scenario's fixed level), coded PER over fading, the retry chain, loss and MAC time
(`linkchain.LinkChain.mcs_rate_loss` with `states`). A pulsed emitter of duty cycle D (its
period long against one packet's retries, short against a packet train) puts each packet in the
jammed state with probability D: the chain's mixture of the SINR (weight D) and SNR (1 - D)
states. Energy-detect deferral of the senders (a jammer above the CCA threshold keeping a
transmitter silent) is not modelled: the jammer acts on the receivers' SINR only.
"""

from __future__ import annotations

import numpy as np

from .budget import LinkParams
from .geometry import LinkGeometry
from .linkchain import LinkChain


def received_dbm(model, eirp_dbm: float, rx_gain_dbi: float, emitter_m, emitter_ground: bool,
                 rx_pos_m, rx_is_bs) -> np.ndarray:
    """Mean received power (dBm) of the emitter at each receiver (k, 3) (module docstring)."""
    rx = np.asarray(rx_pos_m, dtype=float).reshape(-1, 3)
    src = np.broadcast_to(np.asarray(emitter_m, dtype=float).reshape(1, 3), rx.shape)
    geom = LinkGeometry.from_positions(src, rx, np.full(len(rx), bool(emitter_ground)),
                                       np.asarray(rx_is_bs, dtype=bool))
    return float(eirp_dbm) + float(rx_gain_dbi) - model.evaluate(geom, None).loss_db


def sinr_db(snr_db, noise_dbm: float, interference_dbm) -> np.ndarray:
    """SINR (dB) of a link with this SNR when interference I (dBm) adds to the noise floor N."""
    i = np.asarray(interference_dbm, dtype=float)
    signal = np.asarray(snr_db, dtype=float) + noise_dbm
    return signal - 10.0 * np.log10(10.0 ** (noise_dbm / 10.0) + 10.0 ** (i / 10.0))


def combined_dbm(levels_dbm) -> np.ndarray:
    """Several emitters at one receiver: powers add in mW (axis 0 is the emitters)."""
    lv = np.asarray(levels_dbm, dtype=float)
    return 10.0 * np.log10(np.sum(10.0 ** (lv / 10.0), axis=0))


def jammed_chain(chain: LinkChain, snr_db, interference_dbm, duty: float, distance_m,
                 k_db) -> tuple[np.ndarray, np.ndarray, LinkParams]:
    """(SINR dB, MCS, LinkParams) of links under interference with this duty cycle (0-1], through
    the run's own link chain (`Channel.chain`: its noise floor, MCS table, link layer, MCS rule;
    module docstring)."""
    snr = np.atleast_1d(np.asarray(snr_db, dtype=float))
    sinr = sinr_db(snr, chain.budget.noise_dbm, interference_dbm)
    if duty >= 1.0:
        states, weights = [sinr], [1.0]
    else:
        states, weights = [sinr, snr], [duty, 1.0 - duty]
    # the threshold rule picks on the SINR of the duty-averaged interference power
    avg = sinr_db(snr, chain.budget.noise_dbm, np.asarray(interference_dbm, dtype=float) + 10 * np.log10(duty))
    mcs, _, lp = chain.mcs_rate_loss(avg, distance_m, k_db, states=(states, weights))
    return sinr, mcs, lp
