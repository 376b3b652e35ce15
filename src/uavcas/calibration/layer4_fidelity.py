"""Layer 4: RSS distribution fidelity on held-out data, simulation vs each real campaign.

Held out: every real sample compared here was left out of the fits the simulation uses - the
Maeng held-out segments of layer 1 (the profile was fitted on the training segments), the
held-out AFAR flights of layer 3 (the sounder offset was fitted on the training flights), and
the multi-band campaign (never fitted).

One common scale: RSS referred to the twin's budget of layer 3, i.e. a 20 dBm transmitter with
0 dBi antennas, RSS = 20 dBm - path loss:
* Maeng (real): 20 - PL of the held-out samples (layer 1's antenna-compensated target).
* Multi-band (real): same, with its file's budget.
* AFAR (real): held-out flights' sounder power + the layer-3 offset (training flights).
* Sim over AFAR: the layer-3 chain (log-distance + shadowing) over the held-out trajectories.
* Sim over Maeng: the twin's log-distance and Gudmundson shadowing (`channel.LogDistance`,
  `channel.GudmundsonShadowing`, layer 1's profile and decorrelation distance) along the
  held-out Maeng sample sequence of each altitude (tower at its recovered height, UAV at
  (d2D, 0, h): radial geometry, so the shadowing decorrelates with the change of distance and
  height rather than the full path - an approximation, stated).
Both simulations add the twin's small-scale fading sample by sample (Rician, layer 1's K(h)),
since every real sample carries its fast fading.

Hellinger distance H = ||sqrt p - sqrt q|| / sqrt 2 (textbook, in [0, 1]) on 1 dB bins shared by
ALL samples (edges from the minimum to the maximum over every source, so nothing is dropped;
the edges are written to the JSON). A same-distribution floor: H between two random halves of
the held-out Maeng samples (finite-sample noise of the estimate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import ncx2

from uavcas import seeding
from uavcas.channel import GudmundsonShadowing, KFactorProfile, LogDistance, PathLossProfile

from .layer1_fit import Group
from .layer3_link import TX_DBM, Layer3Result
from .metrics import hellinger_on_shared_bins, shared_edges

BIN_DB = 1.0
PAIRS = (
    ("sim_afar", "afar"),
    ("sim_maeng", "maeng"),
    ("sim_afar", "maeng"),
    ("maeng", "afar"),
    ("maeng", "multibw"),
    ("afar", "multibw"),
)


def fading_db(k_db: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Rician power gain samples (dB, E g = 1) for per-sample K (dB)."""
    k = 10.0 ** (np.asarray(k_db, dtype=float) / 10.0)
    g = ncx2.rvs(2, 2.0 * k, random_state=rng) / (2.0 * (k + 1.0))
    return 10.0 * np.log10(g)


def sim_over_groups(groups: list[Group], profile: PathLossProfile, fading: KFactorProfile | None, d_corr_m: float,
                    seed: int, max_samples: int = 4000) -> np.ndarray:
    """RSS of the twin's path loss + shadowing (+ fading) along each group's held-out samples."""
    out = []
    rng = seeding.generator(seed, 4)
    for i, g in enumerate(groups):
        idx = np.flatnonzero(g.test)[:max_samples]
        s = g.samples
        shadow = GudmundsonShadowing(2, d_corr_m, seeding.seed_sequence(seed, 40 + i))
        z = np.empty(idx.size)
        for j, k in enumerate(idx):
            shadow.step(np.array([[0.0, 0.0, g.tx_height_m], [s.d2d_m[k], 0.0, s.height_m[k]]]))
            z[j] = shadow.unit(np.array([[0, 1]]))[0]
        h = s.height_m[idx]
        loss = LogDistance(profile, g.fc_ghz).loss_at_db(s.d3d_m[idx], h) + profile.at(h)[2] * z
        if fading is not None:
            loss = loss - fading_db(fading.at(h), rng)
        out.append(TX_DBM - loss)
    return np.concatenate(out) if out else np.empty(0)


@dataclass
class Layer4Result:
    samples: dict  # source -> RSS (dBm, common scale)
    edges: np.ndarray
    hellinger: dict
    floor: float


def run_layer4(maeng_groups: list[Group], multibw_groups: list[Group], l3: Layer3Result, profile: PathLossProfile,
               fading: KFactorProfile | None = None, d_corr_m: float = 50.0, seed: int = 0) -> Layer4Result:
    rng = seeding.generator(seed)
    test = [r for r in l3.replays if r.name in set(l3.test)]
    sim_afar = np.concatenate([r.rss_chain_dbm["logdistance"] for r in test])
    if fading is not None:
        sim_afar = sim_afar + fading_db(fading.at(np.concatenate([r.alt_m for r in test])), rng)
    samples = {
        "maeng": np.concatenate([TX_DBM - g.target_db[g.test] for g in maeng_groups]),
        "multibw": np.concatenate([TX_DBM - g.pl_db for g in multibw_groups]) if multibw_groups else np.empty(0),
        "afar": np.concatenate([r.measured_db + l3.offset_db["logdistance"] for r in test]),
        "sim_afar": sim_afar,
        "sim_maeng": sim_over_groups(maeng_groups, profile, fading, d_corr_m, seed),
    }
    samples = {k: v for k, v in samples.items() if v.size}
    edges = shared_edges(list(samples.values()), BIN_DB)
    h = {f"{a}|{b}": hellinger_on_shared_bins(samples[a], samples[b], edges)
         for a, b in PAIRS if a in samples and b in samples}
    m = samples["maeng"]
    perm = rng.permutation(m.size)
    floor = hellinger_on_shared_bins(m[perm[: m.size // 2]], m[perm[m.size // 2 :]], edges)
    return Layer4Result(samples, edges, h, floor)


def layer4_json(res: Layer4Result) -> dict:
    return {
        "held_out": "Maeng held-out segments (layer 1), AFAR held-out flights (layer 3), multi-band (never fitted)",
        "scale": f"RSS at {TX_DBM:g} dBm EIRP, 0 dBi (dBm) = {TX_DBM:g} - path loss; AFAR sounder + layer-3 offset",
        "metric": "Hellinger distance, textbook, in [0, 1]",
        "bins": {"width_db": BIN_DB, "lo_dbm": float(res.edges[0]), "hi_dbm": float(res.edges[-1]),
                 "n_bins": int(len(res.edges) - 1)},
        "hellinger": res.hellinger,
        "same_distribution_floor": res.floor,
        "sources": {k: {"n": int(v.size), "mean_dbm": float(v.mean()), "std_db": float(v.std()),
                        "min_dbm": float(v.min()), "max_dbm": float(v.max())} for k, v in res.samples.items()},
    }
