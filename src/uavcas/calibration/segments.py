"""Contiguous flight segments: the held-out split, local means and the fading K estimate.

Held-out split. A measurement file is one flight's time series: neighbouring samples share
their shadowing (decorrelation ~tens of metres, seconds of flight), so a per-sample random
split scores the model on samples whose neighbours it was fitted on. Here each flight is cut
into contiguous blocks of `BLOCK_S` (60 s; about 200 m of flight at the Maeng speed of
3.4 m/s, four shadowing decorrelation distances); a seeded `TEST_FRACTION` (30 %) of the
blocks, per file, is held out; training drops `GUARD_S` (5 s) on each side of every held-out
block so that no training sample sits next to a test sample. Nothing held out is seen by any
fit (path loss, effective antenna pattern, sigma, K, two-ray, offsets).

Local mean. The twin's path-loss model stands for the *local mean* path loss; the fast fading
around it is the link chain's Rician layer (`uavcas.channel.fading`). The local mean over a
window is the power average, PL_lm = -10 log10(mean 10^(-PL/10)) (a dB average would be biased
by E[10 log10 g] < 0 of the fading). Windows are consecutive samples inside one contiguous run
of a split, `LOCAL_MEAN_S` long (5 s: the twin's default window, the interval over which the
emulated link holds one set of parameters); a shorter tail is dropped.

K factor. The moment method of Greenstein, Michelson and Erceg, "Moment-method estimation of
the Ricean K-factor", IEEE Commun. Lett. 3(6), 1999: with gamma = Var(P) / E[P]^2 of the
received power P within a window short enough that the local mean is constant,
K = sqrt(1 - gamma) / (1 - sqrt(1 - gamma)). Windows of `K_WINDOW_S` = 1 s (3.4 m at the
Maeng speed, 40 wavelengths at 3.51 GHz: Lee's local-mean span, W. C. Y. Lee, "Estimate of
local average power of a mobile radio signal", IEEE Trans. Veh. Technol. 34(1), 1985); gamma
is averaged over the windows of one file. RSRP is averaged over the LTE reference signals of
the band, so K is that of the band-averaged power - the quantity a wideband OFDM (802.11)
receiver's decoder effectively sees.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uavcas import seeding

SAMPLE_INTERVAL_S = {"maeng": 0.1, "multibw": 0.25}  # median step of the raw files' time stamps
BLOCK_S = 60.0
GUARD_S = 5.0
TEST_FRACTION = 0.3
LOCAL_MEAN_S = 5.0
K_WINDOW_S = 1.0


@dataclass(frozen=True)
class SegmentSplit:
    train: np.ndarray  # bool per sample
    test: np.ndarray  # bool per sample
    n_blocks: int
    test_blocks: tuple[int, ...]


def contiguous_split(n: int, interval_s: float, seed: int, key: int, block_s: float = BLOCK_S,
                     guard_s: float = GUARD_S, test_fraction: float = TEST_FRACTION) -> SegmentSplit:
    """Seeded held-out blocks of one file (see module docstring); key separates the files."""
    block = max(1, int(round(block_s / interval_s)))
    guard = int(round(guard_s / interval_s))
    n_blocks = max(1, int(np.ceil(n / block)))
    n_test = min(n_blocks - 1, max(1, int(round(test_fraction * n_blocks)))) if n_blocks > 1 else 0
    rng = seeding.generator(seed, key)
    test_blocks = np.sort(rng.permutation(n_blocks)[:n_test])
    is_test = np.zeros(n_blocks, dtype=bool)
    is_test[test_blocks] = True
    test = is_test[np.arange(n) // block]
    near = np.convolve(test.astype(float), np.ones(2 * guard + 1), mode="same") > 0 if guard else test
    return SegmentSplit(train=~near, test=test, n_blocks=n_blocks, test_blocks=tuple(int(b) for b in test_blocks))


def windows(mask: np.ndarray, size: int) -> list[np.ndarray]:
    """Index arrays of `size` consecutive samples inside each contiguous run of `mask`."""
    idx = np.flatnonzero(mask)
    if idx.size == 0 or size < 1:
        return []
    runs = np.split(idx, np.flatnonzero(np.diff(idx) != 1) + 1)
    return [r[j : j + size] for r in runs for j in range(0, len(r) - size + 1, size)]


def window_size(interval_s: float, span_s: float) -> int:
    return max(1, int(round(span_s / interval_s)))


def power_mean_db(loss_db: np.ndarray, wins: list[np.ndarray]) -> np.ndarray:
    """Local-mean loss of each window: -10 log10(mean 10^(-L/10))."""
    x = np.asarray(loss_db, dtype=float)
    return np.array([-10.0 * np.log10(np.mean(10.0 ** (-x[w] / 10.0))) for w in wins])


def window_mean(x: np.ndarray, wins: list[np.ndarray]) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    return np.array([a[w].mean(axis=0) for w in wins]) if wins else np.empty((0,) + a.shape[1:])


def moment_k_db(power_db: np.ndarray, wins: list[np.ndarray]) -> float:
    """Greenstein et al.'s moment-method K (dB) of the power within the windows."""
    p = 10.0 ** (np.asarray(power_db, dtype=float) / 10.0)
    gam = np.mean([np.var(p[w], ddof=1) / np.mean(p[w]) ** 2 for w in wins if len(w) > 1])
    root = np.sqrt(max(1.0 - gam, 0.0))
    return float(10.0 * np.log10(root / (1.0 - root))) if 0.0 < root < 1.0 else (-np.inf if root == 0 else np.inf)
