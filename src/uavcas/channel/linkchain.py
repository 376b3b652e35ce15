"""The link chain: a link's budget from its path loss to its rate, and who hears whom, in one place.

Both consumers call `LinkChain`: the twin's `Channel` (per window, every node pair, with the
run's shadowing and LOS-state processes) and `uavcas channel predict` (a user's geometry, the
model's median loss: `predict_links`). A setting read by one and not the other is therefore
impossible; `tests/channel/test_channel_linkchain.py` checks `channel predict` against a plan.

    path loss PL (median of the model; + shadowing X when the caller has a process for it)
      -> SNR = P_tx + G_tx + G_rx - (PL + X) - N                       (`budget.LinkBudget`)
      -> Rician K(h) at the link's aerial end (None: no fading)         (`fading.KFactorProfile`)
      -> MCS: the fixed level, or adaptive by `selection`
      -> coded PER over the fading, 802.11 retry chain
      -> rate_mbps (the link alone on the channel), delay_ms, loss, mac_time_us
                                                                        (`budget.link_chain`)
    hearing: node u hears node v when P_tx + G_tx + G_rx - (PL + X)(u, v) >= CCA
             (IEEE Std 802.11-2020 17.3.10.6; `airtime.hears_matrix`)
    shared rate: 8 L / sum of E[T] over a link's contention set, with the "dcf" rate model
             (Heusse et al. 2003; `airtime.shared_rate_mbps`); the "phy" model keeps its PHY rate.

The formulas and their sources are in the modules named; this one only fixes their order and
which settings feed each step, so that the two consumers cannot drift apart.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal

import numpy as np

from .airtime import CCA_DBM, hears_matrix, shared_rate_mbps
from .budget import LinkBudget, LinkParams, link_chain
from .fading import KFactorProfile
from .geometry import LinkGeometry
from .linklayer import DEFAULT_LINK_LAYER, LinkLayer
from .mcs import DEFAULT_MARGIN_DB, MCS_80211AG, McsTable, parse_modulation
from .pathloss import PathLossProfile, make_pathloss

Selection = Literal["throughput", "threshold"]


@dataclass(frozen=True, eq=False)
class ChainedLinks:
    """The chain's output for k links; every array has shape (k,).

    `pathloss_db` is the total loss the link sees (shadowing included, when there is any), so
    snr_db = P_tx + G_tx + G_rx - pathloss_db - N holds; the median loss is
    pathloss_db - shadow_db.
    """

    distance_m: np.ndarray  # 3-D
    pathloss_db: np.ndarray
    shadow_db: np.ndarray  # zeros when the caller has no shadowing process (`predict_links`)
    snr_db: np.ndarray
    k_db: np.ndarray | None  # Rician K used per link (None: no fading)
    mcs: np.ndarray  # int
    per: np.ndarray  # first attempt's frame error rate at that MCS (fading-averaged)
    rate_mbps: np.ndarray  # the link alone on the channel; `LinkChain.shared_rate_mbps` shares it
    delay_ms: np.ndarray  # propagation + processing (the MAC time is in the rate)
    loss: np.ndarray  # residual after ARQ
    mac_time_us: np.ndarray  # expected channel time per packet, retries included

    def __len__(self) -> int:
        return len(self.distance_m)

    def columns(self) -> dict[str, np.ndarray | None]:
        """Field name -> array, to build a subclass (`model.LinkArrays`) without copying."""
        return {f.name: getattr(self, f.name) for f in fields(ChainedLinks)}


@dataclass(frozen=True)
class LinkChain:
    """The radio and link-layer settings of a run and the chain over them (module docstring).

    budget: transmit power, antenna gains and noise floor (dBm, dBi).
    link_layer: 802.11 DCF assumptions (`linklayer.LinkLayer`).
    mcs_table: the MCS levels (802.11a/g by default).
    fading: Rician K(h) profile (None: no small-scale fading).
    fixed_mcs: the scenario's fixed level, or None for adaptive.
    selection: adaptive MCS by expected goodput ("throughput", Minstrel's criterion) or by SNR
        threshold + `margin_db` ("threshold", the paper's); see `budget.link_chain`.
    cca_dbm: carrier-sense threshold of the hearing matrix.
    """

    budget: LinkBudget
    link_layer: LinkLayer = DEFAULT_LINK_LAYER
    mcs_table: McsTable = MCS_80211AG
    fading: KFactorProfile | None = None
    fixed_mcs: int | None = None
    selection: Selection = "throughput"
    margin_db: float = DEFAULT_MARGIN_DB
    cca_dbm: float = CCA_DBM

    @classmethod
    def build(
        cls,
        *,
        tx_power_dbm: float = 20.0,
        noise_dbm: float = -95.0,
        tx_gain_dbi: float = 0.0,
        rx_gain_dbi: float = 0.0,
        modulation: str | int = "adaptive",
        margin_db: float = DEFAULT_MARGIN_DB,
        link_layer: LinkLayer | None = None,
        mcs_table: McsTable | None = None,
        fading: KFactorProfile | None = None,
        selection: Selection = "throughput",
        cca_dbm: float = CCA_DBM,
    ) -> LinkChain:
        """The chain from flat settings (a scenario's and a profile's fields; `modulation`:
        "adaptive", a fixed level k or "mcsk")."""
        table = mcs_table or MCS_80211AG
        return cls(
            budget=LinkBudget(tx_power_dbm=tx_power_dbm, tx_gain_dbi=tx_gain_dbi, rx_gain_dbi=rx_gain_dbi,
                              noise_dbm=noise_dbm),
            link_layer=link_layer or DEFAULT_LINK_LAYER,
            mcs_table=table,
            fading=fading,
            fixed_mcs=parse_modulation(modulation, len(table)),
            selection=selection,
            margin_db=float(margin_db),
            cca_dbm=float(cca_dbm),
        )

    def links(self, geometry: LinkGeometry, pathloss_db, shadow_db=None) -> ChainedLinks:
        """The chain for the links of `geometry` with this median loss (+ shadowing, if given)."""
        median = np.asarray(pathloss_db, dtype=float)
        shadow = np.zeros(median.shape) if shadow_db is None else np.asarray(shadow_db, dtype=float)
        total = median if shadow_db is None else median + shadow
        snr = self.budget.snr_db(total)
        k_db = None if self.fading is None else self.fading.at(geometry.h_air_m)
        mcs, reach, lp = self.mcs_rate_loss(snr, geometry.d3d_m, k_db)
        return ChainedLinks(distance_m=geometry.d3d_m, pathloss_db=total, shadow_db=shadow, snr_db=snr, k_db=k_db,
                            mcs=mcs, per=reach[:, 1], rate_mbps=lp.rate_mbps, delay_ms=lp.delay_ms, loss=lp.loss,
                            mac_time_us=lp.mac_time_us)

    def mcs_rate_loss(self, snr_db, distance_m, k_db, states=None) -> tuple[np.ndarray, np.ndarray, LinkParams]:
        """(mcs, reach, LinkParams) from the SNR on: this chain's MCS rule and link layer
        (`budget.link_chain`; `states` = (SNRs, weights) for a link that switches between
        states, e.g. under a pulsed jammer, `interference.jammed_chain`)."""
        return link_chain(snr_db, distance_m, self.mcs_table, self.link_layer, k_db, self.fixed_mcs, self.selection,
                          self.margin_db, states=states)

    def hears(self, n_nodes: int, pairs, pathloss_db) -> np.ndarray:
        """(n, n) bool: node u hears node v at this total loss (pairs not given: deaf)."""
        b = self.budget
        return hears_matrix(n_nodes, pairs, pathloss_db, float(b.tx_power_dbm), b.tx_gain_dbi + b.rx_gain_dbi,
                            self.cca_dbm)

    def shared_rate_mbps(self, links, mac_time_us, hears: np.ndarray) -> np.ndarray | None:
        """Each active air link's share of the DCF airtime among the links it contends with; None
        with the "phy" rate model (the paper's mode keeps its raw PHY rates)."""
        if self.link_layer.rate_model != "dcf":
            return None
        return shared_rate_mbps(links, mac_time_us, hears, self.link_layer.packet_bytes)


def predict_links(model_name: str, pathloss_profile: PathLossProfile, fc_ghz, geometry: LinkGeometry,
                  chain: LinkChain) -> ChainedLinks:
    """The chain on the median loss of model `model_name` (no shadowing, and for a model with a
    LOS state the LOS-probability-weighted mean): what `uavcas channel predict` writes. `fc_ghz`
    is the carrier per link (GHz); links of one carrier share one model object."""
    fc = np.asarray(fc_ghz, dtype=float)
    loss_db = np.empty(len(geometry))
    for f in np.unique(fc):
        rows = fc == f
        part = LinkGeometry(*(getattr(geometry, k.name)[rows] for k in fields(LinkGeometry)))
        loss_db[rows] = make_pathloss(model_name, pathloss_profile, float(f)).loss_db(part)
    return chain.links(geometry, loss_db)
