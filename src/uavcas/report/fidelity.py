"""Fidelity in the dataset report: one row per audited run, each column explained, and the
planned-vs-measured figure.

Reads each run's fidelity.json (DATASET_DIR/runs/<id>/, as a campaign keeps it; `uavcas.fidelity`)
and draws, over all runs: per link direction and window, the measured median hop delay against
the model's (planned delay + FIFO at the planned rate), the distribution of per-hop delay errors,
the measured random loss against the planned loss, and the rate measured on saturated links
against the planned rate.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from uavcas.fidelity.model import Fidelity
from uavcas.figure import plt, png_data_uri

# column of the per-run table -> the sentence that explains it (shown under the table); the
# words follow uavcas.fidelity.audit, .losses and .fifo
COLUMNS: dict[str, str] = {
    "run": "the run's id in the dataset (its row in the run table above).",
    "config": "the run's scenario.",
    "verdict": "pass when every check of the audit holds; fail names the checks that did not "
               "(value and limit, as in fidelity.json's checks). A failed run is kept in the dataset, flagged.",
    "packets": "IP packets followed across the switch captures (each transmission once).",
    "delay error p50 / p90 / p99 (ms)": "per hop crossing (seen at switch i, then at the next switch j), the measured "
                                        "hop delay minus the model's: the planned propagation delay plus a FIFO queue "
                                        "served at the planned rate. Positive: the emulator was late. Limits: |p50| "
                                        "0.1 ms, p90 0.2 ms, p99 0.5 ms, for every swarm size.",
    "lost (packets)": "packets that left a switch towards the next one and never reached it.",
    "queue tail": "of the lost, dropped at the tail of the shaped link's queue because it was full (the port's "
                  "kernel queue-drop counter where the run logged it, else the model's queue at its limit): "
                  "congestion, not chance.",
    "random": "of the lost, dropped by the link's random-loss rule, which realises the plan's residual loss "
              "after retries (as many as the port's loss-rule counter where the run logged it; else every lost "
              "packet the model's queue had room for).",
    "transition": "of the lost, lost within 50 ms of a forwarding change (window change, attack re-routing) or "
                  "on a link leaving the plan; the plan says nothing about packets in flight then.",
    "unexplained": "of the lost, dropped by nothing the port counted: a blackhole at a switch, a wormhole "
                   "detour, no next switch. Expected in attack runs.",
    "random loss sigma": "the loss rules' drops against the planned loss x frames offered, in binomial standard "
                         "deviations (limit 4).",
    "rate ratio": "measured / planned rate on saturated links (the model's queue never empty for 200 ms bins, "
                  "each frame spread over its serialisation time), median over bins (limit 1 +- 0.05); blank "
                  "without a saturated bin.",
    "window change max (ms)": "longest time a window change took to apply (limit 250 ms).",
    "lateness max (ms)": "latest a scheduled event (window change, attack start or stop) ran (limit 100 ms).",
}


def read_run_fidelity(dataset_dir: Path) -> dict[str, Fidelity]:
    """run id -> its audit, for the runs of a dataset that kept one."""
    out = {}
    for path in sorted((Path(dataset_dir) / "runs").glob("*/fidelity.json")):
        try:
            out[path.parent.name] = Fidelity.model_validate_json(path.read_text())
        except ValueError:
            continue  # an unreadable audit is reported as missing, not fatal for the report
    return out


def fidelity_frame(runs: dict[str, Fidelity], configs: dict[str, str], failed: dict[str, str]) -> pd.DataFrame:
    """One row per audited run, the columns of `COLUMNS` (failed: run -> its failed checks' text)."""
    rows = []
    for rid, f in runs.items():
        err = "/".join("-" if x is None else f"{x:.3f}" for x in (f.delay_error_p50_ms, f.delay_error_p90_ms,
                                                                    f.delay_error_p99_ms))
        rows.append({
            "run": rid, "config": configs.get(rid, ""),
            "verdict": f.verdict + (f": {failed.get(rid) or ', '.join(f.failed)}" if f.failed else ""),
            "packets": f.packets, "delay error p50 / p90 / p99 (ms)": err, "lost (packets)": f.lost,
            "queue tail": f.lost_tail, "random": f.lost_random if f.lost_random is not None else f.loss_random_observed,
            "transition": f.lost_transition, "unexplained": f.lost_unexplained,
            "random loss sigma": f.loss_sigma, "rate ratio": f.throughput_ratio_p50,
            "window change max (ms)": f.window_change_max_ms, "lateness max (ms)": f.lateness_max_ms,
        })
    df = pd.DataFrame(rows, columns=list(COLUMNS))
    key = df["run"].map(lambda r: (0, int(r), "") if str(r).isdigit() else (1, 0, str(r)))
    return df.iloc[sorted(range(len(df)), key=lambda i: key.iloc[i])].reset_index(drop=True)


def fidelity_figure(runs: dict[str, Fidelity]) -> str | None:
    """The planned-vs-measured figure over these runs' link-windows, as a data URI (None: no link)."""
    links = [lw for f in runs.values() for lw in f.links if lw.n > 0]
    if not links:
        return None
    # constrained layout keeps every title clear of its neighbour's axis labels
    fig, ax = plt.subplots(2, 2, figsize=(11, 8.5), layout="constrained")
    model = np.array([np.nan if lw.model_delay_p50_ms is None else lw.model_delay_p50_ms for lw in links])
    meas = np.array([np.nan if lw.measured_delay_p50_ms is None else lw.measured_delay_p50_ms for lw in links])
    a = ax[0, 0]
    a.scatter(model, meas, s=6, alpha=0.5)
    hi = float(np.nanmax(np.concatenate([model, meas, [0.1]])))
    a.plot([0, hi], [0, hi], color="k", lw=0.8, label="measured = model")
    a.set(xlabel="model median hop delay (ms)\n(planned delay + FIFO at the planned rate)",
          ylabel="measured median hop delay (ms)", title="hop delay per link direction and window")
    a.legend(fontsize=8)
    a = ax[0, 1]
    for key, label in (("delay_error_p50_ms", "p50"), ("delay_error_p90_ms", "p90"), ("delay_error_p99_ms", "p99")):
        v = np.sort([getattr(lw, key) for lw in links if getattr(lw, key) is not None])
        if v.shape[0]:
            a.plot(v, np.arange(1, v.shape[0] + 1) / v.shape[0], label=label)
    a.set(xscale="symlog", xlabel="per-hop delay error, measured - model (ms, symmetric log)",
          ylabel="fraction of link-windows", title="delay error per link direction and window")
    a.legend(fontsize=8)
    a = ax[1, 0]
    lossy = [lw for lw in links if lw.loss_random is not None]
    a.scatter([lw.planned_loss for lw in lossy], [lw.loss_random for lw in lossy], s=6, alpha=0.5)
    top = max([0.01] + [lw.planned_loss for lw in lossy] + [lw.loss_random for lw in lossy])
    a.plot([0, top], [0, top], color="k", lw=0.8, label="measured = planned")
    a.set(xlabel="planned loss (fraction of frames)", ylabel="measured random loss (fraction of frames)",
          title="random loss per link direction and window")
    a.legend(fontsize=8)
    a = ax[1, 1]
    sat = [(lw.planned_rate_mbps, lw.throughput_ratio_p50) for lw in links if lw.throughput_ratio_p50 is not None]
    if sat:
        a.scatter([s[0] for s in sat], [s[1] for s in sat], s=8)
        a.axhline(1.0, color="k", lw=0.8)
    else:
        a.text(0.5, 0.5, "no saturated link-window", ha="center", va="center", transform=a.transAxes)
    a.set(xlabel="planned rate (Mbit/s)", ylabel="measured / planned rate",
          title="saturated links (median of 200 ms bins)")
    fig.suptitle(f"fidelity: {len(runs)} run(s), {len(links)} link-windows with packets")
    return png_data_uri(fig)
