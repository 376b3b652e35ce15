"""`Channel`: the whole per-window chain for a set of nodes, vectorised over links.

    positions -> LinkGeometry -> path loss (+ LOS state) -> + correlated shadowing -> SNR
              -> MCS (adaptive or fixed) -> coded PER averaged over Rician fading -> ARQ
              -> LinkParams (single-link DCF rate; `airtime` shares it among contenders)

`Channel` holds the part with state: the nodes, the LOS-state and shadowing processes. From the
loss on (SNR, MCS, rate, loss; who hears whom) it calls its `chain` (`linkchain.LinkChain`),
the one assembly of the link budget, which `uavcas channel predict` calls too.

The plan builds one `Channel` per run and calls `evaluate` once per window, in window order,
with every node pair; each call advances the shadowing (and LOS-state) processes by the nodes'
displacement since the previous call, so consecutive windows are correlated as Gudmundson's
model says. Same seed, same node count and same sequence of calls give identical arrays.

Geometry: antenna heights are the node positions' z (the plan puts a BS at z = its profile's
mast height - 10 m, the AERPAW LW1 tower, in the calibrated profile - and UAVs at their altitude). For the 3GPP models
h_UT is the UAV altitude and the BS height comes from its position; UAV-UAV links use each model's documented air-to-air
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

import numpy as np
from scipy.special import ndtr

from uavcas import seeding

from .airtime import CCA_DBM
from .fading import KFactorProfile
from .geometry import LinkGeometry
from .linkchain import ChainedLinks, LinkChain, Selection
from .linklayer import LinkLayer
from .mcs import DEFAULT_MARGIN_DB, McsTable
from .pathloss import PathLossModel, PathLossProfile, make_pathloss
from .shadowing import DEFAULT_DECORRELATION_M, GudmundsonShadowing

# Numbered streams of the channel's seed (uavcas.seeding, int keys); never renumber (it would change every plan).
_SHADOW_STREAM, _LOS_STREAM = 1, 2


@dataclass(frozen=True, eq=False)
class LinkArrays(ChainedLinks):
    """One window's channel for k links: the link chain's arrays (`linkchain.ChainedLinks`, shape
    (k,)) plus the pairs (k, 2), their horizontal distance and LOS state."""

    pairs: np.ndarray  # node indices (a, b) as given
    d2d_m: np.ndarray
    los: np.ndarray | None  # bool, for models with a LOS state (3GPP), else None


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
    link_layer: 802.11 DCF assumptions (`linklayer.LinkLayer`).
    fading: Rician K(h) profile (None: no small-scale fading).
    cca_dbm: carrier-sense threshold of the hearing matrix (`LinkChain.hears`).

    The radio settings build the run's `chain` (`linkchain.LinkChain.build`), which turns each
    window's loss into SNR, MCS, rate and loss, and says which nodes hear each other.
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
        selection: Selection = "throughput",
        cca_dbm: float = CCA_DBM,
    ) -> None:
        if node_names is None and n_nodes is None:
            raise ValueError("give node_names or n_nodes")
        names = tuple(node_names) if node_names is not None else tuple(f"n{i}" for i in range(n_nodes))
        if n_nodes is not None and n_nodes != len(names):
            raise ValueError(f"n_nodes={n_nodes} but {len(names)} node names")
        self.node_names = names
        self.n_nodes = len(names)
        self.model = make_pathloss(pathloss, profile, fc_ghz) if isinstance(pathloss, str) else pathloss
        self.chain = LinkChain.build(
            tx_power_dbm=tx_power_dbm, noise_dbm=noise_dbm, tx_gain_dbi=tx_gain_dbi, rx_gain_dbi=rx_gain_dbi,
            modulation=modulation, margin_db=margin_db, link_layer=link_layer, mcs_table=mcs_table, fading=fading,
            selection=selection, cca_dbm=cca_dbm,
        )
        self.seed = int(seed)
        self._shadow = GudmundsonShadowing(
            self.n_nodes, d_corr_m, seeding.seed_sequence(self.seed, _SHADOW_STREAM)
        )
        self._los = None
        if sample_los and self.model.samples_los:  # the model has a LOS state (pathloss.LosPathLossModel)
            corr_m = self.model.los_corr_m if los_corr_m is None else los_corr_m
            self._los = GudmundsonShadowing(
                self.n_nodes, corr_m, seeding.seed_sequence(self.seed, _LOS_STREAM)
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
        chained = self.chain.links(geom, res.loss_db, shadow)
        return LinkArrays(pairs=pairs, d2d_m=geom.d2d_m, los=res.los, **chained.columns())
