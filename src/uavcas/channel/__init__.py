"""Wireless channel of the twin, vectorised over links with numpy.

positions -> path loss (a model of the `pathloss` registry, one module per model) ->
Gudmundson-correlated shadowing -> SNR (link budget) -> 802.11a/g MCS -> coded BER/PER (BCC union bound) averaged over
Rician fading -> 802.11 ARQ -> LinkParams(rate_mbps, delay_ms, loss, mac_time_us) -> airtime sharing among links in
carrier sense range. `linkchain.LinkChain` assembles the budget from the loss on, and the hearing matrix,
once: `Channel` runs it per window with its shadowing (the twin), `predict_links` on a model's
median loss (`uavcas channel predict`).
"""

from .airtime import CCA_DBM, hears_matrix, shared_rate_mbps
from .budget import LinkBudget, LinkParams, link_params
from .fading import TR36777_UMA_AV_K, KFactorProfile
from .geometry import LinkGeometry, PathLossResult
from .linkchain import ChainedLinks, LinkChain, predict_links
from .linklayer import LinkLayer
from .mcs import MCS_80211AG, McsTable, ber, parse_modulation, per
from .model import Channel, LinkArrays
from .pathloss import (
    PAPER_ANCHORED_PROFILE,
    PAPER_RELATIVE_PROFILE,
    PROFILES,
    FreeSpace,
    LogDistance,
    PathLossModel,
    PathLossProfile,
    RMaAV,
    TwoRay,
    UMaAV,
    UMiAV,
    free_space_loss_db,
    get_profile,
    make_pathloss,
)
from .shadowing import GudmundsonShadowing

__all__ = [
    "CCA_DBM", "KFactorProfile", "PAPER_ANCHORED_PROFILE", "TR36777_UMA_AV_K", "hears_matrix", "shared_rate_mbps",
    "MCS_80211AG", "PAPER_RELATIVE_PROFILE", "PROFILES",
    "ChainedLinks", "Channel", "FreeSpace", "GudmundsonShadowing", "LinkArrays", "LinkBudget", "LinkChain",
    "LinkGeometry",
    "LinkLayer", "LinkParams", "LogDistance", "McsTable", "PathLossModel", "PathLossProfile",
    "PathLossResult", "RMaAV", "TwoRay", "UMaAV", "UMiAV", "ber", "free_space_loss_db",
    "get_profile", "link_params", "make_pathloss", "parse_modulation", "per", "predict_links",
]
