"""Figures of the four layers (matplotlib Agg, PNG, written atomically)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.ticker import NullFormatter

from uavcas import seeding
from uavcas.figure import plt, save_png

from .layer1_pathloss import Layer1Result
from .layer2_mobility import Layer2Result, sim_track
from .layer3_link import Layer3Result
from .layer4_fidelity import Layer4Result

_DPI = 110
_MAX_POINTS = 1500  # per panel: enough to see the cloud, small PNGs


def _binned_median(x, y, edges):
    idx = np.digitize(x, edges) - 1
    xs, ys = [], []
    for k in range(len(edges) - 1):
        m = idx == k
        if m.sum() >= 5:
            xs.append(np.median(x[m]))
            ys.append(np.median(y[m]))
    return np.array(xs), np.array(ys)


def pathloss_figure(res: Layer1Result, path: Path, seed: int = 0) -> Path:
    rng = seeding.generator(seed)
    k = len(res.groups)
    fig, axes = plt.subplots(2, k, figsize=(3.3 * k, 6), sharex="col", gridspec_kw={"height_ratios": [3, 1.3]},
                             squeeze=False)
    for i, g in enumerate(res.groups):
        test = g.test
        d, y = g.samples.d3d_m[test], g.target_db[test]
        pick = rng.choice(d.size, size=min(_MAX_POINTS, d.size), replace=False)
        ax = axes[0, i]
        ax.scatter(d[pick], y[pick], s=2, alpha=0.25, color="0.5", label="measured (held-out)")
        edges = np.geomspace(max(d.min(), 1.0), d.max(), 15)
        for model, style, lab in (("logdistance", "-", "log-distance (fit)"), ("two_ray", "--", "two-ray (fit)"),
                                  ("uma_av", ":", "TR 36.777 UMa-AV")):
            xs, ys = _binned_median(d, res.predictions[(model, "heldout", i)], edges)
            ax.plot(xs, ys, style, lw=1.8, label=lab)
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_title(f"{g.altitude_m:g} m (n={res.profile.n[i]:.2f}, sigma={res.profile.sigma_db[i]:.1f} dB)",
                     fontsize=9)
        r = y - res.predictions[("logdistance", "heldout", i)]
        axr = axes[1, i]
        axr.scatter(d[pick], r[pick], s=2, alpha=0.25, color="0.5")
        axr.axhline(0, color="k", lw=0.8)
        s = res.profile.sigma_db[i]
        axr.fill_between([d.min(), d.max()], -s, s, color="C0", alpha=0.2, label="+-sigma(h)")
        axr.xaxis.set_minor_formatter(NullFormatter())
        axr.set_xlabel("3-D distance (m)")
    axes[0, 0].set_ylabel("path loss (dB)")
    axes[1, 0].set_ylabel("residual (dB)")
    axes[0, 0].legend(fontsize=7, loc="lower right")
    fig.suptitle("Layer 1: Maeng LTE 3.51 GHz held-out segments, path loss vs models (+-sigma: 5 s local-mean spread)")
    return save_png(fig, path, dpi=_DPI)


def crossval_figure(res: Layer1Result, path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(6, 5))
    for j, g in enumerate(res.crossval_groups):
        ax.scatter(res.predictions[("logdistance", "crossval", j)], g.pl_db, s=2, alpha=0.3, label=g.samples.label)
    lo = min(float(np.min(g.pl_db)) for g in res.crossval_groups)
    hi = max(float(np.max(g.pl_db)) for g in res.crossval_groups)
    ax.plot([lo, hi], [lo, hi], "k-", lw=0.8)
    ax.set_xlabel("fitted log-distance prediction (dB)")
    ax.set_ylabel("multi-band measured path loss (dB)")
    ax.legend(fontsize=7, markerscale=4)
    ax.set_title("Layer 1 cross-validation (nothing fitted on these data)")
    return save_png(fig, path, dpi=_DPI)


def mobility_figures(res: Layer2Result, out_dir: Path, seed: int = 0) -> list[Path]:
    kinds = list(res.tracks)
    fig, axes = plt.subplots(2, len(kinds), figsize=(3.6 * len(kinds), 7), squeeze=False, constrained_layout=True)
    fig2, axes2 = plt.subplots(1, len(kinds), figsize=(3.6 * len(kinds), 3.6), squeeze=False, constrained_layout=True)
    params = {k: res.profile.for_kind(k) for k in kinds}
    for i, kind in enumerate(kinds):
        real = res.tracks[kind]["test"][0]
        sims = sim_track(kind, params[kind], real.duration_s, seed + 1, res.area, n_uav=1)
        xy = real.centred_xy()
        axes[0, i].plot(xy[:, 0], xy[:, 1], lw=0.7)
        axes[0, i].set_title(f"{kind}: real {real.name}", fontsize=9)
        sxy = sims[0].centred_xy()
        axes[1, i].plot(sxy[:, 0], sxy[:, 1], lw=0.7, color="C1")
        axes[1, i].set_title(f"{kind}: twin (fitted)", fontsize=9)
        for ax in axes[:, i]:
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_xlabel("x (m)")
        ax2 = axes2[0, i]
        for tr in res.tracks[kind]["test"]:
            s = np.sort(tr.speeds())
            ax2.plot(s, np.linspace(0, 1, s.size), "-", label=f"AFAR {tr.name}")
        s = np.sort(np.concatenate([t.speeds()
                                    for t in sim_track(kind, params[kind], real.duration_s, seed + 1, res.area)]))
        ax2.plot(s, np.linspace(0, 1, s.size), "--", color="k", label="twin")
        ax2.set_title(kind, fontsize=9)
        ax2.set_xlabel("horizontal speed (m/s)")
        ax2.legend(fontsize=7)
    axes2[0, 0].set_ylabel("CDF")
    fig.suptitle("Layer 2: held-out AFAR trajectories vs the twin's fitted missions (centred)")
    fig2.suptitle("Layer 2: speed CDFs, held-out AFAR (solid) vs twin (dashed)")
    return [save_png(fig, out_dir / "mobility_trajectories.png", dpi=_DPI),
            save_png(fig2, out_dir / "mobility_speed_cdf.png", dpi=_DPI)]


def link_figure(res: Layer3Result, path: Path) -> Path:
    rep = next(r for r in res.replays if r.name == res.representative)
    off = res.offset_db["logdistance"]
    fig, ax = plt.subplots(figsize=(10, 4))
    ax.plot(rep.t_s, rep.measured_db + off, lw=0.8, label="measured (sounder + offset)")
    ax.plot(rep.t_s, rep.rss_chain_dbm["logdistance"], lw=0.8, label="twin chain (log-distance + shadowing)")
    ax.plot(rep.t_s, rep.rss_median_dbm["logdistance"], lw=0.8, ls="--", label="twin median loss")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("RSS (dBm at 20 dBm EIRP)")
    ax2 = ax.twinx()
    ax2.plot(rep.t_s, rep.rate_mbps["logdistance"], color="0.4", lw=0.6, alpha=0.6, label="simulated rate")
    ax2.set_ylabel("simulated rate (Mbit/s)")
    r = res.results["logdistance"]["per_flight"][rep.name]["r_chain"]
    ax.set_title(f"Layer 3: flight {rep.name} (held-out), Pearson r = {r:.2f}")
    ax.legend(fontsize=8, loc="lower left")
    return save_png(fig, path, dpi=_DPI)


def fidelity_figure(res: Layer4Result, path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(8, 4.5))
    centres = (res.edges[:-1] + res.edges[1:]) / 2
    for name, v in res.samples.items():
        h, _ = np.histogram(v, bins=res.edges)
        ax.plot(centres, h / h.sum() / np.diff(res.edges), lw=1.2, ls="--" if name.startswith("sim") else "-",
                label=name)
    ax.set_xlabel("RSS at 20 dBm EIRP, 0 dBi (dBm)")
    ax.set_ylabel("PDF (1/dB)")
    txt = ", ".join(f"H({k.replace('|', ',')})={v:.2f}" for k, v in list(res.hellinger.items())[:4])
    ax.set_title("Layer 4: RSS distributions on one scale\n" + txt, fontsize=9)
    ax.legend(fontsize=8)
    return save_png(fig, path, dpi=_DPI)
