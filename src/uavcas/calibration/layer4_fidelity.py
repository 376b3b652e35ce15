"""Layer 4: RSS distribution fidelity, simulation vs each real campaign and real vs real.

One common scale: RSS referred to the twin's budget of layer 3, i.e. a 20 dBm transmitter with
0 dBi antennas, RSS = 20 dBm - path loss:
* Maeng (real): 20 - PL_abs of every sample (layer 1's link budget: antenna-compensated).
* Multi-band (real): same, with its file's budget.
* AFAR (real): sounder power + the layer-3 offset (fitted on training flights), which maps the
  sounder onto exactly this scale.
* Sim over AFAR: the layer-3 chain (log-distance + shadowing) over every AFAR trajectory.
* Sim over Maeng: the same chain over the Maeng sample sequence of each altitude (tower at 10 m,
  UAV at (d2D, 0, h): radial geometry only, so the shadowing decorrelates with the change of
  distance and height rather than the full path - an approximation, stated).

Hellinger distance H = ||sqrt p - sqrt q|| / sqrt 2 (textbook, in [0, 1]) on 1 dB bins shared by
ALL samples (edges from the minimum to the maximum over every source, so nothing is dropped;
the edges are written to the JSON). A same-distribution floor: H between two random halves of
the Maeng samples (finite-sample noise of the estimate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uavcas.channel import Channel, PathLossProfile

from .layer1_pathloss import Group
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


def sim_over_groups(groups: list[Group], profile: PathLossProfile | None, seed: int) -> np.ndarray:
    out = []
    for i, g in enumerate(groups):
        s = g.samples
        ch = Channel(n_nodes=2, pathloss="logdist", profile=profile, seed=seed + i, tx_power_dbm=TX_DBM)
        tower = np.array([0.0, 0.0, g.tx_height_m])
        pairs, is_bs = np.array([[0, 1]]), np.array([True, False])
        loss = np.empty(len(s))
        for k in range(len(s)):
            loss[k] = ch.evaluate(np.vstack([tower, [s.d2d_m[k], 0.0, s.height_m[k]]]), pairs, is_bs).pathloss_db[0]
        out.append(TX_DBM - loss)
    return np.concatenate(out)


@dataclass
class Layer4Result:
    samples: dict  # source -> RSS (dBm, common scale)
    edges: np.ndarray
    hellinger: dict
    floor: float


def run_layer4(maeng_groups: list[Group], multibw_groups: list[Group], l3: Layer3Result,
               profile: PathLossProfile | None, seed: int = 0, max_sim_maeng: int = 4000) -> Layer4Result:
    rng = np.random.default_rng(seed)
    samples = {
        "maeng": np.concatenate([TX_DBM - g.pl_db for g in maeng_groups]),
        "multibw": np.concatenate([TX_DBM - g.pl_db for g in multibw_groups]) if multibw_groups else np.empty(0),
        "afar": np.concatenate([r.measured_db + l3.offset_db["logdistance"] for r in l3.replays]),
        "sim_afar": np.concatenate([r.rss_chain_dbm["logdistance"] for r in l3.replays]),
    }
    # The chain is a Python loop per sample: a contiguous run of each altitude keeps it fast
    # while keeping the shadowing's time order.
    sub = []
    for g in maeng_groups:
        n = len(g.samples)
        k = min(n, max_sim_maeng)
        start = int(rng.integers(0, n - k + 1))
        sub.append(_slice_group(g, slice(start, start + k)))
    samples["sim_maeng"] = sim_over_groups(sub, profile, seed)
    samples = {k: v for k, v in samples.items() if v.size}
    edges = shared_edges(list(samples.values()), BIN_DB)
    h = {f"{a}|{b}": hellinger_on_shared_bins(samples[a], samples[b], edges) for a, b in PAIRS if a in samples and b in samples}
    m = samples["maeng"]
    perm = rng.permutation(m.size)
    floor = hellinger_on_shared_bins(m[perm[: m.size // 2]], m[perm[m.size // 2 :]], edges)
    return Layer4Result(samples, edges, h, floor)


def _slice_group(g: Group, sl: slice) -> Group:
    from dataclasses import replace

    s = g.samples
    s2 = replace(s, rx_dbm=s.rx_dbm[sl], pred_free_dbm=s.pred_free_dbm[sl], d3d_m=s.d3d_m[sl], d2d_m=s.d2d_m[sl],
                 height_m=s.height_m[sl], elev_rad=None, azim_rad=None, ori_rad=None)
    return Group(s2, g.pl_db[sl], g.train[sl], g.tx_height_m, g.fc_ghz)


def layer4_json(res: Layer4Result) -> dict:
    return {
        "scale": f"RSS at {TX_DBM:g} dBm EIRP, 0 dBi (dBm) = {TX_DBM:g} - path loss; AFAR sounder + layer-3 offset",
        "metric": "Hellinger distance, textbook, in [0, 1]",
        "bins": {"width_db": BIN_DB, "lo_dbm": float(res.edges[0]), "hi_dbm": float(res.edges[-1]), "n_bins": int(len(res.edges) - 1)},
        "hellinger": res.hellinger,
        "same_distribution_floor": res.floor,
        "sources": {k: {"n": int(v.size), "mean_dbm": float(v.mean()), "std_db": float(v.std()),
                        "min_dbm": float(v.min()), "max_dbm": float(v.max())} for k, v in res.samples.items()},
    }
