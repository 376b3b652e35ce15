"""Fidelity in the dataset report: per-run verdicts and planned-vs-measured figures.

Reads each run's fidelity.json (DATASET_DIR/runs/<id>/, as a campaign keeps it) and draws, over
all runs: per link direction and window, the measured median hop delay against the model's
(planned delay + FIFO at the planned rate), the measured random loss against the planned loss,
the distribution of per-hop delay errors (p50/p90/p99 per link), and the rate measured on
saturated links against the planned rate.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from uavcas.fidelity.model import Fidelity

from .figure import plt, save_png


def read_run_fidelity(dataset_dir: Path) -> dict[str, Fidelity]:
    """run id -> its audit, for the runs of a dataset that have one."""
    out = {}
    for path in sorted((dataset_dir / "runs").glob("*/fidelity.json")):
        try:
            out[path.parent.name] = Fidelity.model_validate_json(path.read_text())
        except ValueError:
            continue  # an unreadable audit is reported as missing, not fatal for the report
    return out


def draw_fidelity(runs: dict[str, Fidelity], out_dir: Path) -> list[Path]:
    """The planned-vs-measured figures of these runs' audits; returns the PNGs written."""
    links = [lw for f in runs.values() for lw in f.links if lw.n > 0]
    if not links:
        return []
    out_dir.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(2, 2, figsize=(10, 8))
    model = np.array([lw.model_delay_p50_ms for lw in links], dtype=float)
    meas = np.array([lw.measured_delay_p50_ms for lw in links], dtype=float)
    a = ax[0, 0]
    a.scatter(model, meas, s=6, alpha=0.5)
    hi = float(np.nanmax([model.max(), meas.max(), 0.1]))
    a.plot([0, hi], [0, hi], color="k", lw=0.8)
    a.set(xlabel="model (planned delay + FIFO) median hop delay, ms", ylabel="measured median hop delay, ms",
          title="hop delay per link direction and window")
    a = ax[0, 1]
    for key, label in (("delay_error_p50_ms", "p50"), ("delay_error_p90_ms", "p90"), ("delay_error_p99_ms", "p99")):
        v = np.sort([getattr(lw, key) for lw in links if getattr(lw, key) is not None])
        a.plot(v, np.arange(1, v.shape[0] + 1) / v.shape[0], label=label)
    a.set(xscale="symlog", xlabel="per-hop delay error (measured - model), ms", ylabel="fraction of link-windows",
          title="delay error per link direction and window")
    a.legend()
    a = ax[1, 0]
    lossy = [lw for lw in links if lw.loss_random is not None]
    a.scatter([lw.planned_loss for lw in lossy], [lw.loss_random for lw in lossy], s=6, alpha=0.5)
    top = max([0.01] + [lw.planned_loss for lw in lossy] + [lw.loss_random for lw in lossy])
    a.plot([0, top], [0, top], color="k", lw=0.8)
    a.set(xlabel="planned loss", ylabel="measured random loss", title="loss per link direction and window")
    a = ax[1, 1]
    sat = [(lw.planned_rate_mbps, lw.throughput_ratio_p50) for lw in links if lw.throughput_ratio_p50 is not None]
    if sat:
        a.scatter([s[0] for s in sat], [s[1] for s in sat], s=8)
        a.axhline(1.0, color="k", lw=0.8)
    a.set(xlabel="planned rate, Mbit/s", ylabel="measured / planned rate", title="saturated links (median of bins)")
    fig.suptitle(f"fidelity: {len(runs)} run(s), {len(links)} link-windows")
    return [save_png(fig, out_dir / "fidelity.png")]


def fidelity_section(dataset_dir: Path, out: Path, card: dict) -> str:
    """The report's fidelity section (HTML): counts, a table of runs, the figures."""
    runs = read_run_fidelity(dataset_dir)
    counts = card.get("fidelity") or {}
    head = ", ".join(f"{v} {k}" for k, v in counts.items() if v)
    rows = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in (
            rid, f.verdict, ", ".join(f.failed) or "-", f.delay_error_p50_ms, f.delay_error_p90_ms,
            f.delay_error_p99_ms, f.lost, f.lost_tail, f.loss_random_observed)) + "</tr>"
        for rid, f in sorted(runs.items(), key=lambda kv: (kv[1].verdict == "pass", kv[0])))
    table = ("<table><tr>" + "".join(f"<th>{h}</th>" for h in (
        "run", "verdict", "failed checks", "error p50 ms", "p90", "p99", "lost", "queue tail", "random"))
        + "</tr>" + rows + "</table>") if rows else "<p>No run of this dataset kept a fidelity.json.</p>"
    figs = draw_fidelity(runs, out / "fidelity")
    imgs = "".join(f'<p><img src="{html.escape(str(p.relative_to(out)))}" style="max-width:100%"></p>' for p in figs)
    return f"<h2>Fidelity</h2><p>Runs by verdict: {html.escape(head or 'none audited')}</p>{table}{imgs}"
