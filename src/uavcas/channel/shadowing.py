"""Spatially correlated shadowing per link: Gudmundson's AR(1) model.

Gudmundson, "Correlation model for shadow fading in mobile radio systems", Electronics Letters
27(23), 1991: log-normal shadowing along a track decorrelates as rho(dd) = exp(-dd / d_corr).
Sampled at successive positions, this is the AR(1) recursion of the paper (sec. "Shadow Fading"):

    X[k] = rho X[k-1] + sqrt(1 - rho^2) N(0, sigma^2),   rho = exp(-dd / d_corr),  d_corr = 50 m.

We keep the state in units of sigma, Z = X / sigma ~ N(0, 1), and return sigma(h) * Z: with a
constant sigma this is exactly the recursion above, and when sigma changes (the UAV climbs,
3GPP switches between LOS and NLOS sigmas) the shadowing stays stationary with the current
sigma instead of carrying the old variance.

Displacement dd of a link between two moving nodes: the sum of both ends' displacements since
the previous step, |dp_a| + |dp_b|. Shadowing is caused by the obstacles along the path, and the
path changes when either end moves; with a fixed BS this is Gudmundson's mobile-to-BS case
exactly. (The change of the relative vector p_b - p_a would wrongly keep a formation flying in
parallel fully correlated over kilometres.) Positions are sampled once per window, so dd is the
straight-line displacement between samples - the lower bound of the path actually flown.

State: one value per unordered node pair {a, b} for ALL pairs, held as the upper triangle of an
(n, n) array and advanced on every `step` whether or not a pair is asked for, so the result of
a window does not depend on which pairs were active before. The first step draws the stationary
N(0, 1). Random numbers come from a numpy Generator seeded from a SeedSequence: same seed and
same sequence of positions, same values.
"""

from __future__ import annotations

import numpy as np

from uavcas import seeding

DEFAULT_DECORRELATION_M = 50.0


def correlation(displacement_m, d_corr_m: float = DEFAULT_DECORRELATION_M) -> np.ndarray:
    """Gudmundson's normalised autocorrelation exp(-d / d_corr)."""
    return np.exp(-np.abs(np.asarray(displacement_m, dtype=float)) / d_corr_m)


class GudmundsonShadowing:
    """Unit-variance AR(1) shadowing state for every pair of `n_nodes` nodes."""

    def __init__(
        self,
        n_nodes: int,
        d_corr_m: float = DEFAULT_DECORRELATION_M,
        seed: int | np.random.SeedSequence = 0,
    ) -> None:
        if n_nodes < 1:
            raise ValueError("n_nodes must be >= 1")
        if not d_corr_m > 0:
            raise ValueError("d_corr_m must be > 0")
        self.n_nodes = n_nodes
        self.d_corr_m = float(d_corr_m)
        self._rng = seeding.generator(seed)
        self._z: np.ndarray | None = None  # (n, n), upper triangle used
        self._pos: np.ndarray | None = None  # node positions at the last step
        self.steps = 0

    def step(self, pos_m: np.ndarray) -> None:
        """Advance every pair's state to the nodes' new positions (n, 3)."""
        pos = np.asarray(pos_m, dtype=float)
        if pos.shape != (self.n_nodes, 3):
            raise ValueError(f"positions must have shape ({self.n_nodes}, 3), got {pos.shape}")
        innovation = self._rng.standard_normal((self.n_nodes, self.n_nodes))
        if self._z is None:
            self._z = innovation
        else:
            moved = np.linalg.norm(pos - self._pos, axis=1)
            rho = correlation(moved[:, None] + moved[None, :], self.d_corr_m)
            self._z = rho * self._z + np.sqrt(1.0 - rho**2) * innovation
        self._pos = pos.copy()
        self.steps += 1

    def unit(self, pairs: np.ndarray) -> np.ndarray:
        """Current N(0, 1) state of each pair (k, 2); the order inside a pair does not matter."""
        if self._z is None:
            raise RuntimeError("call step(positions) before reading the shadowing state")
        p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        if np.any(p[:, 0] == p[:, 1]):
            raise ValueError("a link needs two different nodes")
        return self._z[np.minimum(p[:, 0], p[:, 1]), np.maximum(p[:, 0], p[:, 1])]

    def __call__(self, pos_m: np.ndarray, pairs: np.ndarray, sigma_db) -> np.ndarray:
        """Advance to `pos_m` and return the shadowing in dB, sigma_db * Z, for `pairs`."""
        self.step(pos_m)
        return np.asarray(sigma_db, dtype=float) * self.unit(pairs)
