"""`uavcas plan CONFIG`: the pure digital-twin plan of one scenario, its summary and figures."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import typer
from rich.table import Table

from uavcas.report.topology import draw_plan_windows

from .common import (
    atomic_write_text,
    check_output,
    config_argument,
    console,
    plan_or_fail,
    profile_option,
    rounds_option,
    seed_option,
    window_s_option,
    windows_option,
)


def plan_cmd(
    config: str = config_argument(),
    seed: int = seed_option("Seed: the same seed and config give the same plan."),
    windows: int = windows_option(),
    window_s: float = window_s_option(),
    rounds: int = rounds_option(),
    profile: str = profile_option(),
    out: Path = typer.Option(None, "--out", help="Write plan.json here."),
    figure: Path = typer.Option(None, "--figure", help="Directory for one topology PNG per window."),
) -> None:
    """Plan a scenario: positions, links and their rate/delay/loss per window, attack schedule."""
    if out is not None:
        check_output(out, "file")
    if figure is not None:
        check_output(figure, "dir", "--figure")
    p = plan_or_fail(config, seed, windows, window_s, profile, rounds)
    print_summary(p)
    if out is not None:
        atomic_write_text(out, p.to_json())
        console.print(f"plan written to {out}")
    if figure is not None:
        paths = draw_plan_windows(p, figure)
        console.print(f"{len(paths)} topology figures written to {figure}")


def print_summary(p) -> None:
    uavs = sum(n.kind == "uav" for n in p.nodes)
    console.print(
        f"[bold]{p.config}[/] seed={p.seed} profile={p.profile}: {uavs} UAVs, "
        f"{len(p.nodes) - uavs} BSs, {len(p.windows)} windows x {p.window_s:g} s"
    )
    t = Table(title="windows", show_lines=False)
    for col in ("window", "t_s", "links", "air", "mean rate Mbit/s", "mean delay ms", "max loss", "max hops",
                "disconnected"):
        t.add_column(col, justify="right")
    mcs_hist: Counter[int] = Counter()
    for w in p.windows:
        air = [lk for lk in w.links if lk.kind == "air"]
        mcs_hist.update(lk.mcs for lk in air)
        t.add_row(
            str(w.index),
            f"{w.t_s:g}",
            str(len(w.links)),
            str(len(air)),
            f"{sum(lk.rate_mbps for lk in air) / max(1, len(air)):.1f}",
            f"{sum(lk.delay_ms for lk in air) / max(1, len(air)):.2f}",
            f"{max((lk.loss for lk in air), default=0):.2e}",
            str(max((len(r.hops) - 1 for r in w.routes), default=0)),
            ", ".join(p.disconnected_uavs(w)) or "-",
        )
    console.print(t)
    console.print(
        f"disconnected: {p.disconnected_fraction:.1%} of UAV-windows (no usable path to any BS; "
        "the runner sends them no benign traffic)"
    )
    console.print(
        "MCS histogram (air links, all windows): "
        + ", ".join(f"MCS{k}: {mcs_hist[k]}" for k in sorted(mcs_hist))
    )
    if not p.attacks:
        console.print("attacks: none (benign)")
    for a in p.attacks:
        console.print(
            f"attack {a.attack_id}: {', '.join(a.attackers) or '(no swarm node)'} -> {', '.join(a.victims)} "
            f"from {a.start_s:.3f} s to {a.stop_s:.3f} s {a.params or ''}"
        )
        # an emitter it places (a jammer) and the link directions whose parameters it changes
        placed = [(w.index, e) for w in p.windows for e in w.interferers if e.attack_id == a.attack_id]
        if placed:
            over = [o for w in p.windows for o in w.link_overrides if o.attack_id == a.attack_id]
            e = placed[0][1]
            console.print(f"  emitter {e.eirp_dbm:g} dBm EIRP at {e.fc_ghz:g} GHz, duty {e.duty:.0%}, "
                          f"{'ground' if e.ground else 'airborne'}, at {e.position} m in window {placed[0][0]}: "
                          f"{len(over)} link-direction overrides in {len(placed)} windows "
                          f"(worst SINR {min((o.sinr_db for o in over), default=float('nan')):.1f} dB)")


def register(app: typer.Typer) -> None:
    app.command("plan")(plan_cmd)
