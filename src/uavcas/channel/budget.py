"""Link budget and link-layer model: path loss -> SNR -> (MCS, BER, PER) -> LinkParams.

SNR (dB, per link; links are reciprocal, so one value serves both directions):

    SNR = P_tx + G_tx + G_rx - (PL + X_shadow) - N

P_tx from the scenario (10 or 30 dBm in the paper campaign); G_tx = G_rx = 0 dBi by default:
the AERPAW path-loss fit is on gain-compensated data and the paper states no antenna gains, so
isotropic antennas keep the paper's chain "TX power - path loss - noise" (a 2.15 dBi dipole
pair would add 4.3 dB); N = noise floor in dBm, a configuration value (-95 dBm by default, the
scenario's noise field).

Link layer: 802.11a/g OFDM DCF, IEEE Std 802.11-2020 (Clause 17 PHY, Clause 10 MAC), for a
packet of `packet_bytes` (1500, the IP MTU the emulation carries) in an MPDU with 36 octets of
MAC overhead (24 header + 8 LLC/SNAP + 4 FCS):

    T_data(rate)  = 16 + 4 + 4 ceil((16 + 8 L_mpdu + 6) / N_DBPS) us        (TXTIME, 17.4.3)
    T_ack         = same for the 14-octet ACK at the highest basic rate <= data rate (6/12/24)
    T_k           = DIFS + E[backoff_k] + T_data + SIFS + T_ack              (attempt k = 0, 1, ...)
    DIFS = SIFS + 2 slot = 34 us, SIFS = 16 us, slot = 9 us,
    E[backoff_k] = slot * min(2^k (CWmin + 1) - 1, CWmax) / 2, CWmin = 15, CWmax = 1023.

A failed attempt is charged like a successful one (its ACK timeout, SIFS + slot + 25 us PHY
RX-start delay = 50 us, is within about 10 us of SIFS + T_ack = 44..60 us). With PER p per
attempt and `retry_limit` R retransmissions:

    loss      = p^(R + 1)                                   (residual loss after ARQ)
    E[T]      = sum_{k=0..R} p^k T_k                        (expected MAC time per packet)
    rate_mbps = 8 packet_bytes / E[T]                       (rate_model "dcf")
              = PHY rate of the MCS                         (rate_model "phy", the paper's)
    delay_ms  = d / c + processing_delay_ms                 (what the shaper adds as latency)

The MAC time is counted once: the shaper serialises every packet at rate_mbps, so a 1500-byte
packet already spends 8 * 1500 / rate = E[T] in the link's queue (`uavcas.emulation.shaping`,
HTB); adding E[T] to delay_ms as well counted it twice (0.4-24 ms too much per full frame).
Small packets (TCP ACKs) pass faster than their real MAC time, as the shaper has no fixed
per-packet cost; full frames, which carry the traffic, are exact.
`mac_time_us` = E[T] is returned for the airtime sharing (`uavcas.channel.airtime`), which
divides the capacity among links that hear each other; the shaper's rate is the shared one.

Retry chain and fading (`uavcas.channel.frames`): attempt k happens with probability reach_k
(= p^k above when every attempt uses one level and there is no fading); attempts after
`fallback_after` (4) use the lowest level, as 802.11 rate control's retry chain ends at the base
rate; with small-scale fading the retries of a packet see one fading gain and reach_k is
averaged over the window's Rician distribution (pass `k_db`; None = no fading). In general

    loss = reach_{R+1},   E[T] = sum_{k=0..R} reach_k T_k(c_k),   rate = 8 L / E[T].

PER: the coded PER of `uavcas.channel.mcs` (802.11 BCC, union bound) at SNR minus the 5 dB
implementation loss the 802.11 sensitivities assume (`implementation_loss_db`), on the whole
MPDU, as the FCS covers it. `coding="uncoded"` keeps the paper's uncoded BER.

MCS choice (`link_chain`). Fixed: the scenario's level. Adaptive, selection "throughput" (the
default): the level with the highest expected throughput as 802.11 rate control measures it
(Linux mac80211 Minstrel, ns-3 `MinstrelWifiManager`): the level's success ratio (frames
delivered at it / attempts made at it, its retries included) times the bits it carries per
transmission time 8 L / T_0(m), under the window's fading; the retry chain then handles the
failures. Selection "threshold": the paper's rule, the highest level whose SNR threshold +
margin is met (`McsTable.select`); with fading it keeps levels whose deep fades lose many
frames.

"dcf" is the default: the emulated link should carry what an 802.11a link carries, which at
54 Mbit/s with 1500-byte packets is about 30 Mbit/s (cf. Jun, Peddabachagari & Sichitiu,
"Theoretical maximum throughput of IEEE 802.11 and its applications", NCA 2003), and a lossy
link spends channel time on retries. `retry_limit` defaults to 6: dot11ShortRetryLimit = 7
counts transmission *attempts* (802.11-2020 Annex C; ns-3's FrameRetryLimit likewise), i.e.
one transmission and 6 retries. retry_limit=0, rate_model="phy", coding="uncoded",
implementation_loss_db=0, fallback_after=None and no fading reproduce the paper's raw chain (loss = PER, rate = PHY
rate). `processing_delay_ms` (0.1 ms) stands for the radio's driver/firmware hand-off per hop;
the emulated kernel adds its own real forwarding cost on top.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict
from scipy.constants import c as SPEED_OF_LIGHT_M_S

from .frames import attempt_levels, attempt_reach
from .linklayer import DEFAULT_LINK_LAYER, LinkLayer
from .mcs import MCS_80211AG, McsTable

# IEEE 802.11-2020 Clause 17 OFDM PHY characteristics (20 MHz) and Clause 10 DCF timing.
SLOT_US = 9.0
SIFS_US = 16.0
DIFS_US = SIFS_US + 2 * SLOT_US
CW_MIN = 15
CW_MAX = 1023
PREAMBLE_US = 16.0
SIGNAL_US = 4.0
SYMBOL_US = 4.0
SERVICE_BITS, TAIL_BITS = 16, 6
ACK_BYTES = 14
MANDATORY_BASIC_RATES_MBPS = (6.0, 12.0, 24.0)  # ACK rate rule, 802.11-2020 10.6.6.5.2


class LinkBudget(BaseModel):
    """Radio parameters shared by all links of a scenario."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    tx_power_dbm: float = 20.0
    tx_gain_dbi: float = 0.0
    rx_gain_dbi: float = 0.0
    noise_dbm: float = -95.0

    def rx_power_dbm(self, loss_db) -> np.ndarray:
        return self.tx_power_dbm + self.tx_gain_dbi + self.rx_gain_dbi - np.asarray(loss_db, dtype=float)

    def snr_db(self, loss_db) -> np.ndarray:
        """SNR for a total loss (path loss + shadowing) in dB."""
        return self.rx_power_dbm(loss_db) - self.noise_dbm


@dataclass(frozen=True, eq=False)
class LinkParams:
    """What the emulator applies to each link (both directions), one entry per link."""

    rate_mbps: np.ndarray
    delay_ms: np.ndarray
    loss: np.ndarray
    mac_time_us: np.ndarray  # E[T]: expected channel time per packet, retries included


def ppdu_airtime_us(payload_bits, n_dbps) -> np.ndarray:
    """TXTIME of an OFDM PPDU (802.11-2020 17.4.3), 20 MHz channel."""
    bits = SERVICE_BITS + np.asarray(payload_bits) + TAIL_BITS
    return PREAMBLE_US + SIGNAL_US + SYMBOL_US * np.ceil(bits / np.asarray(n_dbps))


def attempt_time_us(mcs, table: McsTable, link: LinkLayer, attempt: int) -> np.ndarray:
    """Channel time of attempt `attempt` (0 = first): DIFS + mean backoff + DATA + SIFS + ACK."""
    mcs = np.asarray(mcs)
    rate = table.rate_mbps[mcs]
    basic = np.array(MANDATORY_BASIC_RATES_MBPS)
    ack_rate = basic[np.searchsorted(basic, rate, side="right") - 1]
    ack_ndbps = table.n_dbps[np.searchsorted(table.rate_mbps, ack_rate)]
    cw = min((CW_MIN + 1) * 2**attempt - 1, CW_MAX)
    return (
        DIFS_US
        + SLOT_US * cw / 2.0
        + ppdu_airtime_us(link.mpdu_bits, table.n_dbps[mcs])
        + SIFS_US
        + ppdu_airtime_us(8 * ACK_BYTES, ack_ndbps)
    )


def link_params(
    snr_db,
    mcs,
    distance_m,
    table: McsTable = MCS_80211AG,
    link: LinkLayer = DEFAULT_LINK_LAYER,
    k_db=None,
) -> LinkParams:
    """Rate, delay and residual loss per link from its SNR and MCS (formulas: module docstring);
    `k_db`: Rician K factor per link (None: no fading)."""
    mcs = np.asarray(mcs, dtype=np.int64)
    return link_params_from_reach(attempt_reach(snr_db, mcs, table, link, k_db), mcs, distance_m, table, link)


def link_chain(
    snr_db,
    distance_m,
    table: McsTable = MCS_80211AG,
    link: LinkLayer = DEFAULT_LINK_LAYER,
    k_db=None,
    fixed_mcs: int | None = None,
    selection: Literal["throughput", "threshold"] = "throughput",
    margin_db: float = 3.0,
    states: tuple[Sequence, Sequence[float]] | None = None,
) -> tuple[np.ndarray, np.ndarray, LinkParams]:
    """(mcs, reach, LinkParams) per link: the MCS choice of the module docstring, then the link
    layer at that MCS (`reach[:, 1]` is the first attempt's PER).

    `states` = (SNRs, weights): a link whose SNR switches between states while a packet train
    lasts (a pulsed jammer: SINR while it is on, SNR while it is off), state k with time share
    weights[k] (summing to 1); `snr_db` is then only what the threshold selection picks on. Each
    packet's retry chain sees one state (the switching is slow against a packet's attempts, fast
    against the train), so the attempt probabilities are the weighted mean of the states':
    reach = sum_k w_k reach_k; the MCS choice, loss and MAC time follow from that mean as from
    one state's (Minstrel judges a level by its success over many packets, i.e. by this mean).
    None: the one state `snr_db`."""
    snrs_in, w_in = states if states is not None else ([snr_db], [1.0])
    snrs = [np.atleast_1d(np.asarray(x, dtype=float)) for x in snrs_in]
    w = [float(x) for x in w_in]
    if len(snrs) != len(w) or not snrs or abs(sum(w) - 1.0) > 1e-9 or min(w) < 0:
        raise ValueError("link_chain: states need one weight >= 0 per SNR, summing to 1")

    def reach_at(mcs: np.ndarray) -> np.ndarray:
        out = w[0] * attempt_reach(snrs[0], mcs, table, link, k_db)
        for snr, wk in zip(snrs[1:], w[1:]):
            out = out + wk * attempt_reach(snr, mcs, table, link, k_db)
        return out

    if fixed_mcs is not None or selection == "threshold":
        sel = np.atleast_1d(np.asarray(snr_db, dtype=float))
        mcs = np.full(sel.shape, fixed_mcs, dtype=np.int64) if fixed_mcs is not None else table.select(sel, margin_db)
        reach = reach_at(mcs)
        return mcs, reach, link_params_from_reach(reach, mcs, distance_m, table, link)
    best = None
    for m in range(len(table)):
        mcs = np.full(snrs[0].shape, m, dtype=np.int64)
        reach = reach_at(mcs)
        # Minstrel's success ratio of a rate: frames delivered at it / attempts made at it (its
        # retries sit in the same fade, so an aggressive rate also pays for its failed retries).
        n_at = link.retry_limit + 1 if link.fallback_after is None else min(link.fallback_after, link.retry_limit + 1)
        ratio = (1.0 - reach[:, n_at]) / reach[:, :n_at].sum(axis=1)
        tput = ratio / attempt_time_us(mcs, table, link, 0)
        if best is None:
            best = (tput, mcs, reach)
            continue
        better = tput > best[0]  # ties keep the more robust level
        best = (np.where(better, tput, best[0]), np.where(better, mcs, best[1]),
                np.where(better[:, None], reach, best[2]))
    mcs, reach = best[1], best[2]
    return mcs, reach, link_params_from_reach(reach, mcs, distance_m, table, link)


def link_params_from_per(
    per_, mcs, distance_m, table: McsTable = MCS_80211AG, link: LinkLayer = DEFAULT_LINK_LAYER
) -> LinkParams:
    """`link_params` for one given per-attempt PER used by every attempt (no fading, no fallback)."""
    p = np.atleast_1d(np.asarray(per_, dtype=float))
    reach = p[:, None] ** np.arange(link.retry_limit + 2)
    return link_params_from_reach(reach, mcs, distance_m, table, link.model_copy(update={"fallback_after": None}))


def link_params_from_reach(
    reach, mcs, distance_m, table: McsTable = MCS_80211AG, link: LinkLayer = DEFAULT_LINK_LAYER
) -> LinkParams:
    """LinkParams from the attempt probabilities reach_k, k = 0..retry_limit + 1."""
    r = np.asarray(reach, dtype=float)
    levels = attempt_levels(np.broadcast_to(np.asarray(mcs, dtype=np.int64), r.shape[:1]), link)
    expected_us = np.zeros(r.shape[0])
    for k in range(link.retry_limit + 1):
        expected_us += r[:, k] * attempt_time_us(levels[:, k], table, link, k)
    loss = np.clip(r[:, link.retry_limit + 1], 0.0, 1.0)  # every attempt failed
    if link.rate_model == "dcf":
        rate = 8.0 * link.packet_bytes / expected_us
    else:
        rate = table.rate_mbps[levels[:, 0]].astype(float)
    delay = np.broadcast_to(np.asarray(distance_m, dtype=float) / SPEED_OF_LIGHT_M_S * 1e3 + link.processing_delay_ms,
                            r.shape[:1]).astype(float)
    return LinkParams(rate_mbps=rate, delay_ms=delay, loss=loss, mac_time_us=expected_us)
