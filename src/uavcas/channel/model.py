"""`Channel`: the whole per-window chain for a set of nodes, vectorised over links.

    positions -> LinkGeometry -> path loss (+ LOS state) -> + correlated shadowing -> SNR
              -> MCS (adaptive or fixed) -> coded PER averaged over Rician fading -> ARQ
              -> LinkParams (single-link DCF rate; `airtime` shares it among contenders)

The plan builds one `Channel` per run and calls `evaluate` once per window, in window order,
with every node pair; each call advances the shadowing (and LOS-state) processes by the nodes'
displacement since the previous call, so consecutive windows are correlated as Gudmundson's
model says. Same seed, same node count and same sequence of calls give identical arrays.

Geometry: antenna heights are the node positions' z (the plan puts a BS at z = its profile's
mast height - 10 m, the AERPAW LW1 tower, in the calibrated profile - and UAVs at their altitude). For the 3GPP models h_UT is the UAV altitude and
the BS height comes from its position; UAV-UAV links use each model's documented air-to-air
rule (see `geometry`, `pathloss.logdist` and `pathloss.tr36777`: the aerial end's altitude for
log-distance, the LOS branch for TR 36.777).

LOS state (models with `samples_los`, the 3GPP ones): sampled per link as LOS iff U < P_LOS
with U = Phi(Z), where Z is a
second Gudmundson process (unit variance; correlation distance `los_corr_m`, by default the
model's LOS/NLOS-state correlation distance of TR 38.901 Table 7.6.3.1-2: 50 m for UMa and UMi,
60 m for RMa). This is the spirit of TR 38.901's spatially consistent LOS state (sec. 7.6.3.3)
in AR(1) form: the marginal P(LOS) is exactly P_LOS, yet a link does not flip between LOS and
NLOS (a 20+ dB jump) every window while its geometry barely changes. `sample_los=False` uses
the LOS-probability-weighted mean loss instead (`los` is then None).

Fading: with a `fading` K profile (`uavcas.channel.fading.KFactorProfile`) the window's loss,
MAC time and rate are expectations over Rician fading with K(h) at the link's aerial end;
fading=None keeps the SNR as it is (no small-scale fading).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.special import ndtr

from .budget import LinkBudget, LinkLayer, link_chain
from .fading import KFactorProfile
from .geometry import LinkGeometry
from .mcs import DEFAULT_MARGIN_DB, MCS_80211AG, McsTable, parse_modulation
from .pathloss import PathLossModel, PathLossProfile, make_pathloss
from .shadowing import DEFAULT_DECORRELATION_M, GudmundsonShadowing

# SeedSequence([seed, stream]) streams; never renumber (it would change every plan).
_SHADOW_STREAM, _LOS_STREAM = 1, 2


@dataclass(frozen=True, eq=False)
class LinkArrays:
    """One window's channel for k links; every array has shape (k,) (pairs: (k, 2)).

    `pathloss_db` is the total loss the link sees, shadowing included, so that
    snr_db = P_tx + G_tx + G_rx - pathloss_db - N holds; the model's median loss is
    pathloss_db - shadow_db.
    """

    pairs: np.ndarray  # node indices (a, b) as given
    distance_m: np.ndarray  # 3-D
    d2d_m: np.ndarray
    pathloss_db: np.ndarray
    shadow_db: np.ndarray
    snr_db: np.ndarray
    mcs: np.ndarray  # int
    per: np.ndarray  # first attempt's frame error rate at that MCS (fading-averaged)
    rate_mbps: np.ndarray  # the link alone on the channel; `airtime` divides it among contenders
    delay_ms: np.ndarray  # propagation + processing (the MAC time is in the rate)
    loss: np.ndarray  # residual after ARQ
    mac_time_us: np.ndarray  # expected channel time per packet, retries included
    k_db: np.ndarray | None  # Rician K used per link (None: no fading)
    los: np.ndarray | None  # bool, for models with a LOS state (3GPP), else None

    def __len__(self) -> int:
        return len(self.pairs)


class Channel:
    """Channel chain of one run.

    Parameters
    ----------
    node_names / n_nodes: the nodes (indices into `pos` in `evaluate`); give either.
    pathloss: a registered name (`pathloss.names()`) or a model.
    profile: log-distance profile (object or name; default ``paper-anchored``); ignored by the
        other models.
    seed: seeds the shadowing and LOS-state processes (independent streams).
    tx_power_dbm, noise_dbm, tx_gain_dbi, rx_gain_dbi: the link budget.
    modulation: "adaptive", a fixed level k or "mcsk".
    margin_db: adaptive-MCS margin of the "threshold" selection (paper: 3 dB).
    selection: adaptive MCS by expected goodput ("throughput", Minstrel's criterion) or by SNR
        threshold + margin ("threshold", the paper's); see `budget.link_chain`.
    d_corr_m: shadowing decorrelation distance (paper: 50 m).
    los_corr_m: LOS-state correlation distance (3GPP models; default: the model's).
    sample_los: draw a LOS state (3GPP models) rather than use the LOS-weighted mean loss.
    link_layer: 802.11 DCF assumptions (`budget.LinkLayer`).
    fading: Rician K(h) profile (None: no small-scale fading).
    """

    def __init__(
        self,
        node_names: Sequence[str] | None = None,
        *,
        n_nodes: int | None = None,
        pathloss: str | PathLossModel = "logdist",
        profile: PathLossProfile | str | None = None,
        seed: int = 0,
        tx_power_dbm: float = 20.0,
        noise_dbm: float = -95.0,
        modulation: str | int = "adaptive",
        d_corr_m: float = DEFAULT_DECORRELATION_M,
        fc_ghz: float | None = None,
        tx_gain_dbi: float = 0.0,
        rx_gain_dbi: float = 0.0,
        margin_db: float = DEFAULT_MARGIN_DB,
        link_layer: LinkLayer | None = None,
        los_corr_m: float | None = None,
        sample_los: bool = True,
        mcs_table: McsTable | None = None,
        fading: KFactorProfile | None = None,
        selection: Literal["throughput", "threshold"] = "throughput",
    ) -> None:
        if node_names is None and n_nodes is None:
            raise ValueError("give node_names or n_nodes")
        names = tuple(node_names) if node_names is not None else tuple(f"n{i}" for i in range(n_nodes))
        if n_nodes is not None and n_nodes != len(names):
            raise ValueError(f"n_nodes={n_nodes} but {len(names)} node names")
        self.node_names = names
        self.n_nodes = len(names)
        self.model = make_pathloss(pathloss, profile, fc_ghz) if isinstance(pathloss, str) else pathloss
        self.budget = LinkBudget(
            tx_power_dbm=tx_power_dbm, tx_gain_dbi=tx_gain_dbi, rx_gain_dbi=rx_gain_dbi, noise_dbm=noise_dbm
        )
        self.table = mcs_table or MCS_80211AG
        self.fixed_mcs = parse_modulation(modulation, len(self.table))
        self.margin_db = float(margin_db)
        self.link_layer = link_layer or LinkLayer()
        self.fading = fading
        self.selection = selection
        self.seed = int(seed)
        self._shadow = GudmundsonShadowing(
            self.n_nodes, d_corr_m, np.random.SeedSequence([self.seed, _SHADOW_STREAM])
        )
        self._los = None
        if sample_los and self.model.samples_los:  # the model has a LOS state (pathloss.LosPathLossModel)
            corr_m = self.model.los_corr_m if los_corr_m is None else los_corr_m
            self._los = GudmundsonShadowing(
                self.n_nodes, corr_m, np.random.SeedSequence([self.seed, _LOS_STREAM])
            )

    def _check(self, pos, pairs, node_is_bs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pos = np.asarray(pos, dtype=float)
        if pos.shape != (self.n_nodes, 3) or not np.all(np.isfinite(pos)):
            raise ValueError(f"pos must be a finite ({self.n_nodes}, 3) array, got shape {pos.shape}")
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        bad = pairs.size and (pairs.min() < 0 or pairs.max() >= self.n_nodes)
        if bad or np.any(pairs[:, 0] == pairs[:, 1]):
            raise ValueError("pairs must hold two different node indices in 0..n_nodes-1")
        is_bs = np.asarray(node_is_bs, dtype=bool)
        if is_bs.shape != (self.n_nodes,):
            raise ValueError(f"node_is_bs must have shape ({self.n_nodes},), got {is_bs.shape}")
        return pos, pairs, is_bs

    def evaluate(self, pos: np.ndarray, pairs: np.ndarray, node_is_bs: np.ndarray) -> LinkArrays:
        """Advance to this window's positions (n, 3) and return the links `pairs` (k, 2)."""
        pos, pairs, is_bs = self._check(pos, pairs, node_is_bs)
        a, b = pairs[:, 0], pairs[:, 1]
        geom = LinkGeometry.from_positions(pos[a], pos[b], is_bs[a], is_bs[b])
        los_u = None
        if self._los is not None:
            self._los.step(pos)
            los_u = ndtr(self._los.unit(pairs))  # Phi(Z): uniform marginal, correlated in time
        res = self.model.evaluate(geom, los_u)
        shadow = self._shadow(pos, pairs, res.sigma_db)
        total = res.loss_db + shadow
        snr = self.budget.snr_db(total)
        k_db = None if self.fading is None else self.fading.at(geom.h_air_m)
        mcs, reach, lp = link_chain(snr, geom.d3d_m, self.table, self.link_layer, k_db, self.fixed_mcs,
                                    self.selection, self.margin_db)
        return LinkArrays(
            pairs=pairs,
            distance_m=geom.d3d_m,
            d2d_m=geom.d2d_m,
            pathloss_db=total,
            shadow_db=shadow,
            snr_db=snr,
            mcs=mcs,
            per=reach[:, 1],
            rate_mbps=lp.rate_mbps,
            delay_ms=lp.delay_ms,
            loss=lp.loss,
            mac_time_us=lp.mac_time_us,
            k_db=k_db,
            los=res.los,
        )
