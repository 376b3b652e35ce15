"""The plan's jammed link parameters: per window, what an attack's emitter does to each link.

For a window [t0, t1) and an attack whose emitter (`AttackFamily.emitter`, e.g. the jammer of
`attacks.jamming`) is on during part of it, [start_s, stop_s) = the attack's span within the
window:

1. the emitter's mean power at every node, through the run's path-loss model and the receiver's
   antenna gain (`channel.interference.received_dbm`), at its position of that window;
2. per direction src -> dst of every active air link, the SINR at the receiver dst and the
   link's chain under it (`channel.interference.jammed_chain`: MCS, fading-averaged PER, retry
   chain, loss and MAC time; a duty cycle below 1 as the mixture of the jammed and clear states);
3. the rate: with the DCF rate model, the airtime share of the window's contention sets
   (`channel.airtime`) recomputed with the jammed MAC times: rate = 8 L / sum over the direction's
   contention set, where its own link counts with the direction's jammed E[T] and every other
   link with the mean of its two directions' (one contender carries both; `airtime` takes the
   two directions as one). So a jammed neighbour's retries slow a link the jammer does not
   reach, as on one channel. With the PHY rate model, the jammed MCS's rate. Delay is the
   propagation and processing delay, which jamming does not change.
4. a direction gets a `LinkOverride` when the change is material: the MCS differs, or the rate
   by at least MATERIAL_RATE_REL of the unjammed rate, or the loss by at least MATERIAL_LOSS
   (absolute). Smaller changes are left unshaped (they are below what a run's audit can tell
   from the unjammed plan over a few seconds of traffic) and the link is not jammed there.

One emitter per attack; a composition holds at most one attack of a family, so emitters of two
attacks would be two families' and are evaluated each alone.
"""

from __future__ import annotations

import numpy as np

from uavcas.channel.airtime import contention_sets
from uavcas.channel.interference import jammed_chain, received_dbm

from .model import Attack, Interferer, Link, LinkOverride

MATERIAL_RATE_REL = 0.10  # a rate change of at least 10 % of the unjammed rate
MATERIAL_LOSS = 0.01  # a loss change of at least 1 percentage point


def material(mcs0: int | None, rate0: float, loss0: float, mcs: int, rate: float, loss: float) -> bool:
    """The rule of step 4 (module docstring)."""
    return (mcs0 is not None and mcs != mcs0) or rate_or_loss_changed(rate0, loss0, rate, loss)


def rate_or_loss_changed(rate0: float, loss0: float, rate: float, loss: float) -> bool:
    """The rate by >= MATERIAL_RATE_REL of the unjammed rate, or the loss by >= MATERIAL_LOSS."""
    return abs(rate - rate0) >= MATERIAL_RATE_REL * rate0 or abs(loss - loss0) >= MATERIAL_LOSS


def window_interference(channel, emitters, w: int, t0: float, t1: float, names: list[str], pos: np.ndarray,
                        is_bs: np.ndarray, links: list[Link], arr, pair_index: dict, hears: np.ndarray, prof,
                        ) -> tuple[list[Interferer], list[LinkOverride]]:
    """(interferers, overrides) of window w for `emitters`: [(Attack, attacks.Emitter)]; `hears`
    is the window's hearing matrix (`channel.chain.hears`), the one the unjammed rates shared."""
    c = prof.channel
    air = [lk for lk in links if lk.kind == "air"]
    idx = {x: k for k, x in enumerate(names)}
    ends = np.array([(idx[lk.a], idx[lk.b]) for lk in air], dtype=np.int64).reshape(-1, 2)
    kk = np.array([pair_index[(int(a), int(b))] for a, b in ends], dtype=np.int64)
    contend = contention_sets(ends, hears).astype(float)
    interferers, overrides = [], []
    for attack, em in emitters:
        start, stop = max(attack.start_s, t0), min(attack.stop_s, t1)
        if not stop > start:
            continue
        where = np.asarray(em.positions_m[w], dtype=float)
        interferers.append(Interferer(attack_id=attack.attack_id, position=tuple(_r(x, 3) for x in where),
                                      ground=em.ground, eirp_dbm=float(em.eirp_dbm), duty=float(em.duty),
                                      fc_ghz=float(c.fc_ghz), start_s=_r(start, 6), stop_s=_r(stop, 6)))
        if not air:
            continue
        overrides += _overrides(channel, attack, em, where, start, stop, pos, is_bs, air, ends, kk, arr, contend, prof)
    return interferers, overrides


def _overrides(channel, attack: Attack, em, where, start, stop, pos, is_bs, air, ends, kk, arr, contend, prof):
    c = prof.channel
    at_node = received_dbm(channel.model, em.eirp_dbm, c.rx_gain_dbi, where, em.ground, pos, is_bs)
    # directions: a -> b (receiver b) for every air link, then b -> a (receiver a)
    rx = np.r_[ends[:, 1], ends[:, 0]]
    k2 = np.r_[kk, kk]
    k_db = None if arr.k_db is None else arr.k_db[k2]
    sinr, mcs, lp = jammed_chain(channel.chain, arr.snr_db[k2], at_node[rx], em.duty, arr.distance_m[k2], k_db)
    m = len(air)
    if c.link_layer.rate_model == "dcf":
        t_dir = lp.mac_time_us
        t_link = 0.5 * (t_dir[:m] + t_dir[m:])  # one contender per link: its two directions' mean
        busy = contend @ t_link  # (m,): each link's contention set, its own mean included
        own = np.r_[np.arange(m), np.arange(m)]
        rate = 8.0 * c.link_layer.packet_bytes / (busy[own] - t_link[own] + t_dir)
    else:
        rate = lp.rate_mbps
    names_dir = [(lk.a, lk.b) for lk in air] + [(lk.b, lk.a) for lk in air]
    out = []
    for d, (src, dst) in enumerate(names_dir):
        lk = air[d % m]
        r, loss = _r(rate[d], 4), min(1.0, max(0.0, _r(lp.loss[d], 8)))
        if not material(lk.mcs, lk.rate_mbps, lk.loss, int(mcs[d]), r, loss):
            continue
        out.append(LinkOverride(attack_id=attack.attack_id, src=src, dst=dst, start_s=_r(start, 6),
                                stop_s=_r(stop, 6), interference_dbm=_r(at_node[rx[d]], 3), sinr_db=_r(sinr[d], 3),
                                mcs=int(mcs[d]), rate_mbps=r, delay_ms=lk.delay_ms, loss=loss))
    return out


def _r(x: float, nd: int) -> float:
    return float(round(float(x), nd))
