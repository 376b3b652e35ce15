"""Modulation and coding: the 802.11a/g MCS table, MCS selection, BER (uncoded and after the
convolutional decoder) and PER.

The table (``data/mcs_80211ag.csv``) holds the paper's seven levels (table ``tab:mcs``) with
their IEEE Std 802.11-2020 Clause 17 parameters, including the minimum receiver sensitivity of
Table 17-18 (-82, -81, -79, -77, -74, -70, -65 dBm for 6, 9, 12, 18, 24, 36, 54 Mbit/s).

SNR thresholds. A sensitivity is a received power; what a receiver needs is an SNR. The table's
sensitivities are set against thermal noise in the 20 MHz channel plus the receiver noise
figure the 802.11 OFDM numbers are built on (10 dB; the remaining 5 dB "implementation margin"
is part of the sensitivity and therefore stays inside the threshold):

    N_ref = kT0 * B + NF = -174 dBm/Hz + 10 log10(20e6 Hz) + 10 dB = -90.99 dBm
    threshold_db = sensitivity_dbm - N_ref   ->  8.99, 9.99, 11.99, 13.99, 16.99, 20.99, 25.99 dB

(-174 dBm/Hz is kT0 at T0 = 290 K, rounded as link budgets conventionally do.) These are SNRs at
which a real receiver still delivers PER < 10 % on 1000-octet frames.

Selection. Adaptive: the highest level whose threshold + margin (3 dB, the paper's value) is
met. Below MCS0's threshold + margin the link still uses MCS0 - 802.11 has nothing slower, and
the link's loss then comes out of the BER/PER model instead of the link vanishing (routing,
not the channel, decides which links exist). Fixed: the given level whatever the SNR.

BER. Uncoded Gray-mapped BER on Es/N0 = SNR (Proakis & Salehi, Digital Communications, 5th ed.,
sec. 4.3; the paper's equation): BPSK Q(sqrt(2 SNR)); square M-QAM (M >= 4)
4/log2(M) (1 - 1/sqrt(M)) Q(sqrt(3 SNR / (M - 1))), which for M = 4 reduces to the exact QPSK
per-bit BER Q(sqrt(SNR)) = BPSK at the same Eb/N0 (`ber`).

Coding (`coded_ber`). 802.11a/g protects the bits with the K = 7 (133, 171) binary convolutional
code (BCC, IEEE Std 802.11-2020 17.3.5.6), punctured to 2/3 and 3/4, decoded by Viterbi. The
decoded BER is the union bound over the code's distance spectrum with hard decisions
(Proakis & Salehi 5th ed. sec. 8.2; Bhattacharyya parameter D = sqrt(4 p (1 - p)) of the
uncoded bit error rate p):

    Pb <= 1 / (2 b) * sum_d c_d D^d          (b = 1, 2, 3 for rates 1/2, 2/3, 3/4)

with the information weights c_d of Haccoun & Begin, "High-rate punctured convolutional codes
for Viterbi and sequential decoding", IEEE Trans. Commun. 37(11), 1989 (rate 1/2: d = 10, 12,
..., 26; 2/3: d = 6..15; 3/4: d = 5..14). This is the "NIST" OFDM error model of ns-3
(G. Pei and T. R. Henderson, "Validation of OFDM error rate model in ns-3", Boeing Research &
Technology, 2010; ns-3 `NistErrorRateModel`). The code rate therefore counts: BPSK 1/2 and BPSK 3/4 differ by ~2.9 dB at
PER 10 %. PER = 1 - (1 - Pb)^L over the L bits of a frame.

Implementation loss. The AWGN curves of the bound reach PER 10 % on 1000-octet frames at 3.9,
6.7, 6.9, 9.8, 13.4, 16.5, 22.5 dB for the seven levels; the thresholds above are 5.1, 3.3,
5.1, 4.2, 3.6, 4.5, 3.5 dB higher because the 802.11 sensitivities hold a 5 dB implementation
margin on top of the 10 dB noise figure (see "SNR thresholds" above). The link layer applies
that margin (`LinkLayer.implementation_loss_db`, 5 dB) before the bound, so a link at its selection
threshold has PER of the order of 10 % as the standard's numbers say, not ~0.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Literal

import numpy as np
from scipy.special import erfc

DEFAULT_TABLE_FILE = "mcs_80211ag.csv"
THERMAL_NOISE_DBM_PER_HZ = -174.0  # kT0, T0 = 290 K
REFERENCE_BANDWIDTH_HZ = 20e6  # 802.11a/g channel spacing the sensitivities are specified for
REFERENCE_NOISE_FIGURE_DB = 10.0
DEFAULT_MARGIN_DB = 3.0  # the paper's adaptive-MCS margin
DEFAULT_FRAME_BITS = 1500 * 8

Modulation = Literal["adaptive"] | int


def reference_noise_dbm(
    bandwidth_hz: float = REFERENCE_BANDWIDTH_HZ, noise_figure_db: float = REFERENCE_NOISE_FIGURE_DB
) -> float:
    """Noise power the 802.11 sensitivities are referred to: kT0 B + NF (dBm)."""
    return THERMAL_NOISE_DBM_PER_HZ + 10.0 * np.log10(bandwidth_hz) + noise_figure_db


@dataclass(frozen=True, eq=False)
class McsTable:
    """The MCS levels as parallel arrays, index = MCS number (0 = most robust)."""

    modulation: tuple[str, ...]
    order: np.ndarray  # constellation size M
    code_rate: np.ndarray
    rate_mbps: np.ndarray  # PHY data rate
    n_dbps: np.ndarray  # data bits per 4 us OFDM symbol (802.11-2020 Table 17-4)
    sensitivity_dbm: np.ndarray
    snr_threshold_db: np.ndarray
    source: str

    def __post_init__(self) -> None:
        if np.any(np.diff(self.snr_threshold_db) <= 0) or np.any(np.diff(self.rate_mbps) <= 0):
            raise ValueError("MCS levels must have strictly increasing rates and SNR thresholds")

    def __len__(self) -> int:
        return len(self.modulation)

    @classmethod
    def load(
        cls,
        path: str | Path | None = None,
        noise_ref_dbm: float | None = None,
    ) -> McsTable:
        """Read a table file (CSV, '#' comment lines); thresholds = sensitivity - noise_ref_dbm."""
        if path is None:
            text = resources.files("uavcas.channel").joinpath("data", DEFAULT_TABLE_FILE).read_text()
            source = f"uavcas/channel/data/{DEFAULT_TABLE_FILE}"
        else:
            text, source = Path(path).read_text(), str(path)
        rows = list(csv.DictReader(line for line in text.splitlines() if not line.startswith("#")))
        if [int(r["mcs"]) for r in rows] != list(range(len(rows))):
            raise ValueError(f"{source}: MCS indices must be 0..{len(rows) - 1} in order")
        ref = reference_noise_dbm() if noise_ref_dbm is None else noise_ref_dbm
        sens = np.array([float(r["sensitivity_dbm"]) for r in rows])
        return cls(
            modulation=tuple(r["modulation"] for r in rows),
            order=np.array([int(r["order"]) for r in rows]),
            code_rate=np.array([float(r["code_rate"]) for r in rows]),
            rate_mbps=np.array([float(r["rate_mbps"]) for r in rows]),
            n_dbps=np.array([int(r["n_dbps"]) for r in rows]),
            sensitivity_dbm=sens,
            snr_threshold_db=sens - ref,
            source=source,
        )

    def select(self, snr_db: np.ndarray, margin_db: float = DEFAULT_MARGIN_DB) -> np.ndarray:
        """Adaptive MCS: highest level with snr >= threshold + margin; MCS0 below all of them."""
        snr = np.asarray(snr_db, dtype=float)
        met = snr[..., None] >= self.snr_threshold_db + margin_db  # thresholds increase
        return np.maximum(met.sum(axis=-1) - 1, 0).astype(np.int64)

    def choose(
        self,
        snr_db: np.ndarray,
        modulation: Modulation | str = "adaptive",
        margin_db: float = DEFAULT_MARGIN_DB,
    ) -> np.ndarray:
        """MCS per link for a scenario's modulation field: "adaptive", k or "mcsk" (fixed)."""
        fixed = parse_modulation(modulation, len(self))
        if fixed is None:
            return self.select(snr_db, margin_db)
        return np.full(np.shape(snr_db), fixed, dtype=np.int64)

    def ber(self, snr_db: np.ndarray, mcs: np.ndarray) -> np.ndarray:
        """Uncoded BER of each link's constellation at its SNR (see module docstring)."""
        return ber(snr_db, self.order[np.asarray(mcs)])

    def coded_ber(self, snr_db: np.ndarray, mcs: np.ndarray) -> np.ndarray:
        """BER after Viterbi decoding of each link's level at its SNR (`coded_ber`)."""
        m = np.asarray(mcs)
        return coded_ber(snr_db, self.order[m], self.code_rate[m])


def parse_modulation(modulation: Modulation | str, n_levels: int = 7) -> int | None:
    """None for adaptive, else the fixed level (accepts 3 or "mcs3")."""
    if modulation == "adaptive":
        return None
    if isinstance(modulation, str) and modulation.startswith("mcs"):
        modulation = modulation[3:]
    try:
        level = int(modulation)
    except (TypeError, ValueError):
        raise ValueError(f"modulation must be 'adaptive' or an MCS level, got {modulation!r}") from None
    if not 0 <= level < n_levels:
        raise ValueError(f"fixed MCS {level} outside 0..{n_levels - 1}")
    return level


def q_function(x: np.ndarray) -> np.ndarray:
    """Gaussian tail Q(x) = erfc(x / sqrt 2) / 2."""
    return 0.5 * erfc(np.asarray(x, dtype=float) / np.sqrt(2.0))


def ber(snr_db: np.ndarray, order: np.ndarray | int) -> np.ndarray:
    """Uncoded Gray BER on Es/N0 = snr_db: BPSK for order 2, square M-QAM (Proakis) for M >= 4."""
    snr = 10.0 ** (np.asarray(snr_db, dtype=float) / 10.0)
    m = np.asarray(order, dtype=float)
    if np.any((m != 2) & ((m < 4) | (np.sqrt(m) % 1 != 0))):
        raise ValueError("order must be 2 (BPSK) or a square M-QAM size (4, 16, 64, ...)")
    bpsk = q_function(np.sqrt(2.0 * snr))
    m_q = np.where(m == 2, 4.0, m)  # placeholder M for the BPSK entries, discarded below
    qam = 4.0 / np.log2(m_q) * (1.0 - 1.0 / np.sqrt(m_q)) * q_function(np.sqrt(3.0 * snr / (m_q - 1.0)))
    return np.minimum(np.where(m == 2, bpsk, qam), 0.5)


# Information weights c_d of the K = 7 (133, 171) BCC and its punctured rates (Haccoun & Begin
# 1989; ns-3 NistErrorRateModel): rate -> (b, first distance, distance step, c_d).
_BCC_SPECTRA: dict[float, tuple[int, int, int, tuple[int, ...]]] = {
    0.5: (1, 10, 2, (36, 211, 1404, 11633, 77433, 502690, 3322763, 21292910, 134365911)),
    round(2 / 3, 6): (2, 6, 1, (3, 70, 285, 1276, 6160, 27128, 117019, 498860, 2103891, 8784123)),
    0.75: (3, 5, 1, (42, 201, 1492, 10469, 62935, 379644, 2253373, 13073811, 75152755, 428005675)),
}


def viterbi_ber(uncoded_ber: np.ndarray, code_rate: np.ndarray | float) -> np.ndarray:
    """Union bound on the decoded BER of the 802.11 BCC (hard decisions), capped at 0.5."""
    p = np.clip(np.asarray(uncoded_ber, dtype=float), 0.0, 0.5)
    rate = np.broadcast_to(np.round(np.asarray(code_rate, dtype=float), 6), p.shape)
    out = np.full(p.shape, np.nan)
    d_par = np.sqrt(4.0 * p * (1.0 - p))
    for r, (b, d0, step, weights) in _BCC_SPECTRA.items():
        m = rate == r
        if not m.any():
            continue
        dm = d_par[m]
        out[m] = sum(c * dm ** (d0 + step * i) for i, c in enumerate(weights)) / (2.0 * b)
    if np.isnan(out).any():
        raise ValueError(f"no BCC distance spectrum for code rate(s) {sorted(set(rate[np.isnan(out)].tolist()))}")
    return np.minimum(out, 0.5)


def coded_ber(snr_db: np.ndarray, order: np.ndarray | int, code_rate: np.ndarray | float) -> np.ndarray:
    """Decoded BER of an 802.11 OFDM level: `ber` of its constellation through `viterbi_ber`."""
    return viterbi_ber(ber(snr_db, order), code_rate)


def per(ber_: np.ndarray, frame_bits: int | np.ndarray = DEFAULT_FRAME_BITS) -> np.ndarray:
    """Frame error rate 1 - (1 - BER)^L, computed as -expm1(L log1p(-BER)) to keep tiny PERs."""
    b = np.clip(np.asarray(ber_, dtype=float), 0.0, 1.0)
    with np.errstate(divide="ignore"):
        return -np.expm1(np.asarray(frame_bits, dtype=float) * np.log1p(-b))


MCS_80211AG = McsTable.load()
