"""`uavcas audit RUN_DIR`: the run's fidelity, followed packet by packet (uavcas.fidelity).

Writes RUN_DIR/fidelity.json and the summary in run.json (the same audit `uavcas run` makes at
the end of every run, here with tolerances of your choice). Exit 0 when the run passes, 1 when
it fails a check, 2 on bad input.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from uavcas.fidelity import Tolerances, write_fidelity
from uavcas.flows import CaptureError
from uavcas.rundir import RunDir, RunDirError

from .common import console, fail, run_dir_argument


def fidelity_line(s) -> str:
    """One line for a run.json fidelity summary."""
    if s.verdict == "error":
        return f"fidelity: error ({s.error})"
    figures = "/".join("-" if v is None else f"{v:.3f}" for v in
                       (s.delay_error_p50_ms, s.delay_error_p90_ms, s.delay_error_p99_ms))
    failed = f" ({', '.join(s.failed)})" if s.failed else ""
    return f"fidelity: {s.verdict}{failed}; per-hop delay error p50/p90/p99 {figures} ms"


def audit_cmd(
    run_dir: Path = run_dir_argument("A run directory (uavcas run --out)."),
    p50_ms: float = typer.Option(None, "--p50-ms", help="Limit on |median| per-hop delay error (default 0.1)."),
    p90_ms: float = typer.Option(None, "--p90-ms", help="Limit on the p90 per-hop delay error (default 0.2)."),
    p99_ms: float = typer.Option(None, "--p99-ms",
                                 help="Limit on the p99 per-hop delay error (default 0.5)."),
    loss_sigma: float = typer.Option(None, "--loss-sigma", help="Random loss: standard deviations allowed (4)."),
    throughput_rel: float = typer.Option(None, "--throughput-rel", help="Saturated links: |rate/planned - 1| (0.05)."),
    window_change_ms: float = typer.Option(None, "--window-change-ms", help="Longest window change (100)."),
    lateness_ms: float = typer.Option(None, "--lateness-ms", help="Latest scheduled event (100)."),
    links: int = typer.Option(8, "--links", min=0, help="Show this many worst link directions."),
) -> None:
    """Audit a run's timing, loss and rate fidelity against its plan; write fidelity.json."""
    rd = RunDir(run_dir)
    if not rd.root.is_dir():
        raise fail(f"{run_dir}: not a directory")
    try:
        rd.read_plan()  # fails here on a directory without a plan
        if not rd.pcaps():
            raise fail(f"{run_dir}: no captures in {rd.pcap_dir}")
        overrides = {k: v for k, v in {
            "delay_error_p50_ms": p50_ms, "delay_error_p90_ms": p90_ms, "delay_error_p99_ms": p99_ms,
            "loss_sigma": loss_sigma, "throughput_rel": throughput_rel, "window_change_ms": window_change_ms,
            "lateness_ms": lateness_ms}.items() if v is not None}
        tol = Tolerances(**overrides)
        f = write_fidelity(rd.root, tol)
    except (RunDirError, CaptureError, ValueError) as e:
        raise fail(str(e).splitlines()[0]) from None

    checks = Table(title=f"fidelity of {run_dir}: {f.verdict.upper()}", title_justify="left")
    for col in ("check", "value", "limit", "ok"):
        checks.add_column(col)
    for ch in f.checks:
        checks.add_row(ch.name, "-" if ch.value is None else f"{ch.value:.4g}", f"{ch.limit:g}",
                       "[green]ok[/]" if ch.ok else "[red]FAIL[/]")
    console.print(checks)
    console.print(f"{f.n} hop crossings of {f.packets} packets; lost {f.lost} (queue tail {f.lost_tail}, "
                  f"random {f.lost_random}, window change {f.lost_transition}, unexplained {f.lost_unexplained}); "
                  f"loss rules dropped {f.loss_random_observed} of {f.loss_offered} vs "
                  f"{f.loss_random_expected:.1f} planned; gaps moved p50/p90 {f.gaps.shift_p50_ms} / "
                  f"{f.gaps.shift_p90_ms} ms", highlight=False)
    if links:
        worst = sorted((lw for lw in f.links if lw.delay_error_p99_ms is not None),
                       key=lambda lw: -lw.delay_error_p99_ms)[:links]
        t = Table(title="worst link directions (p99 delay error)", title_justify="left")
        for col in ("link", "window", "crossings", "planned ms", "measured p50", "error p50/p90/p99 ms", "lost"):
            t.add_column(col)
        for lw in worst:
            t.add_row(f"{lw.src}>{lw.dst}", str(lw.window), str(lw.n), f"{lw.planned_delay_ms:.3f}",
                      f"{lw.measured_delay_p50_ms}", f"{lw.delay_error_p50_ms}/{lw.delay_error_p90_ms}/"
                      f"{lw.delay_error_p99_ms}", str(lw.lost))
        console.print(t)
    console.print(f"wrote {rd.fidelity_json}", highlight=False)
    if f.verdict != "pass":
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    app.command("audit")(audit_cmd)
