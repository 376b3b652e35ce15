"""3-D Gauss–Markov random walk with reflection on the six faces of the area.

Model (per axis, Liang & Haas 1999; Camp et al. 2002), at the reference step dt0 = `step_s`:
    v_k = a v_{k-1} + (1 - a) vbar + sqrt(1 - a^2) sigma w_k,     x_k = x_{k-1} + v_k dt
Time scaling: the walk is the exact discretisation of an Ornstein–Uhlenbeck velocity with
correlation time tau = -dt0 / ln(alpha), so at a simulation step dt we use
    a_dt = alpha ** (dt / dt0),  sigma unchanged (stationary variance kept),  vbar unchanged.
Velocity statistics per second of flight are then the same for any dt (tested).

Mean speed honoured: `mean_speed_mps` is E|v_xy|. |v_xy| of a per-axis Gaussian is Rician with
parameters (nu = |vbar_xy|, sigma_h); nu is solved from the Rician mean (see `rician_mean_mps`).
Reflection: when a position leaves the box on an axis it is mirrored back and that axis'
velocity *and* mean velocity change sign (the UAV's preferred direction turns away from the
wall). Sign flips keep |v| and |vbar| per axis, so the stationary speed law — and therefore the
configured mean speed — is unchanged by the walls (tested against the configured value).

Speed limit (`max_speed_mps`, optional): the position advances with the state velocity scaled
down to the limit where its horizontal speed exceeds it - an autopilot's speed cap; the state
walk is unchanged, so its statistics below the cap are the model's, and the mean speed is then
the capped one (lower than `mean_speed_mps`).

Simulation runs vectorised over UAVs on a fixed internal grid (`sim_step_s`), extended lazily in
fixed-size chunks so results never depend on query order; positions in between are linearly
interpolated (the box is convex, so they stay inside).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq
from scipy.special import i0e, i1e

from uavcas import seeding
from uavcas.mobility.area import Area, reflect_into
from uavcas.mobility.base import MissionBase, seeded_anchors
from uavcas.mobility.params import GaussMarkovParams

_CHUNK_STEPS = 128  # fixed chunk of random draws (64 s at 0.5 s: one chunk covers a 60 s plan)
_RAYLEIGH_MEAN = np.sqrt(np.pi / 2.0)


def alpha_at_step(alpha: float, step_s: float, dt_s: float) -> float:
    """Memory coefficient at step dt for a walk fitted with `alpha` at step `step_s`."""
    return float(alpha ** (dt_s / step_s)) if alpha > 0 else 0.0


def rician_mean_mps(nu_mps: float | np.ndarray, sigma_mps: float) -> np.ndarray:
    """E|v| of a 2-D Gaussian velocity with mean magnitude nu and per-axis sd sigma.

    sigma sqrt(pi/2) L_{1/2}(-nu^2 / 2 sigma^2), written with exponentially scaled Bessel
    functions so it is stable for large nu/sigma.
    """
    nu = np.asarray(nu_mps, dtype=float)
    if sigma_mps <= 0:
        return np.abs(nu)
    q = nu * nu / (2.0 * sigma_mps * sigma_mps)
    return sigma_mps * _RAYLEIGH_MEAN * ((1.0 + q) * i0e(q / 2.0) + q * i1e(q / 2.0))


def horizontal_mean_velocity(mean_speed_mps: float, sigma_mps: float) -> tuple[float, float]:
    """(nu, sigma_h): mean-velocity magnitude and horizontal per-axis sd giving E|v_xy| = mean_speed.

    If even nu = 0 gives too high a mean (Rayleigh mean sigma sqrt(pi/2) > mean_speed), sigma_h is
    lowered to mean_speed / sqrt(pi/2) — the mean speed is the quantity we promise to honour.
    """
    if mean_speed_mps <= 0:
        return 0.0, 0.0
    if sigma_mps * _RAYLEIGH_MEAN >= mean_speed_mps:
        return 0.0, mean_speed_mps / _RAYLEIGH_MEAN
    nu = brentq(lambda n: float(rician_mean_mps(n, sigma_mps)) - mean_speed_mps, 0.0, mean_speed_mps, xtol=1e-12)
    return float(nu), float(sigma_mps)


def _capped(v: np.ndarray, vmax: float) -> np.ndarray:
    """Velocities (n, 3) with the horizontal part scaled down to speed vmax where faster."""
    h = np.hypot(v[:, 0], v[:, 1])
    scale = np.where(h > vmax, vmax / np.maximum(h, 1e-300), 1.0)
    out = v.copy()
    out[:, :2] *= scale[:, None]
    return out


class GaussMarkovMission(MissionBase):
    kind = "random"

    def __init__(self, n_uav: int, params: GaussMarkovParams | None = None, area: Area | None = None,
                 seed: seeding.SeedLike = 0):
        if n_uav < 1:
            raise ValueError(f"n_uav must be >= 1, got {n_uav}")
        self.n_uav = int(n_uav)
        self.params = p = params or GaussMarkovParams()
        self.area = area or Area()
        self.dt_s = p.sim_step_s
        self.max_speed_mps = p.max_speed_mps
        self.alpha_dt = alpha_at_step(p.alpha, p.step_s, self.dt_s)
        sigma = float(np.sqrt(p.sigma2_mps2))
        self.nu_mps, sigma_h = horizontal_mean_velocity(p.mean_speed_mps, sigma)
        sigma_z = float(np.sqrt(p.sigma2_z_mps2)) if p.sigma2_z_mps2 is not None else sigma
        self.sigma_mps = np.array([sigma_h, sigma_h, sigma_z])  # stationary sd per axis
        self._noise_sd = np.sqrt(1.0 - self.alpha_dt**2) * self.sigma_mps

        anchors_ss, heading_ss, noise_ss = seeding.as_seed_sequence(seed).spawn(3)
        lo, hi = self.area.lo_m, self.area.hi_m
        pad = np.minimum(np.array([p.margin_m, p.margin_m, p.margin_m]), (hi - lo) / 2.0)
        x0 = seeded_anchors(seeding.generator(anchors_ss), self.n_uav, lo + pad, hi - pad, p.min_separation_m)
        heading = seeding.generator(heading_ss).random(self.n_uav) * 2.0 * np.pi
        mu = np.empty((self.n_uav, 3))
        mu[:, 0] = self.nu_mps * np.cos(heading)
        mu[:, 1] = self.nu_mps * np.sin(heading)
        mu[:, 2] = p.mean_vz_mps
        self._rng = seeding.generator(noise_ss)
        # Start in the stationary law so statistics hold from t = 0, not after a burn-in.
        v0 = mu + self.sigma_mps * self._rng.standard_normal((self.n_uav, 3))
        self._x = [x0[None]]  # chunks of positions at grid times k*dt, k = 0..K
        self._v = []  # chunks of velocities used on [k dt, (k+1) dt)
        self._state = (x0.copy(), v0, mu)
        self._n_steps = 0
        self._X = x0[None]
        self._V = np.empty((0, self.n_uav, 3))

    def _extend(self, n_steps_needed: int) -> None:
        lo, hi = self.area.lo_m, self.area.hi_m
        a, dt = self.alpha_dt, self.dt_s
        while self._n_steps < n_steps_needed:
            x, v, mu = self._state
            w = self._rng.standard_normal((_CHUNK_STEPS, self.n_uav, 3))
            xs = np.empty((_CHUNK_STEPS, self.n_uav, 3))
            vs = np.empty((_CHUNK_STEPS, self.n_uav, 3))
            first = self._n_steps == 0
            for k in range(_CHUNK_STEPS):
                if not (first and k == 0):  # the first step flies the stationary initial v0
                    v = a * v + (1.0 - a) * mu + self._noise_sd * w[k]
                fly = v if self.max_speed_mps is None else _capped(v, self.max_speed_mps)
                vs[k] = fly
                x, flip = reflect_into(x + fly * dt, lo, hi)
                if flip.any():
                    sign = np.where(flip, -1.0, 1.0)
                    v = v * sign
                    mu = mu * sign
                xs[k] = x
            self._state = (x, v, mu)
            self._x.append(xs)
            self._v.append(vs)
            self._n_steps += _CHUNK_STEPS
        if self._X.shape[0] != self._n_steps + 1:
            self._X = np.concatenate(self._x, axis=0)
            self._V = np.concatenate(self._v, axis=0)

    def _positions(self, t: np.ndarray) -> np.ndarray:
        u = t / self.dt_s
        k = np.floor(u).astype(np.int64)
        self._extend(int(k.max()) + 1)
        frac = (u - k)[:, None, None]
        return (1.0 - frac) * self._X[k] + frac * self._X[k + 1]

    def velocities(self, t_s: float | np.ndarray) -> np.ndarray:
        """Velocity flown (m/s) at t (the step containing t, speed limit applied); same shapes as
        positions. On a step where the UAV hit a wall this is the pre-reflection velocity."""
        t = np.asarray(t_s, dtype=float)
        if not np.all(np.isfinite(t)) or np.any(t < 0):
            raise ValueError("t_s must be finite and >= 0")
        k = np.floor(np.atleast_1d(t) / self.dt_s).astype(np.int64)
        self._extend(int(k.max()) + 1)
        out = self._V[k]
        return out[0] if t.ndim == 0 else out
