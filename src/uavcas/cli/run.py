"""`uavcas run CONFIG --out DIR`: plan a scenario and realise it in real time on real stacks.

Everything that can be checked without creating anything is checked first (the scenario, root,
tools, namespaces, the output directory); any failure is one line on stderr and exit 2. Then
the kernel is probed (in a throw-away namespace the probe removes) for the shaper backend.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from uavcas.emulation.preflight import preflight, probe_kernel
from uavcas.emulation.runner import RunOptions, realize
from uavcas.events import AttackLogged, AttackRate, RunDone, SetupDone, WindowApplied
from uavcas.fidelity import audit_run
from uavcas.traffic.apps import MAVLINK_PAYLOADS
from uavcas.twin.model import DEFAULT_STREAM_HZ, MAX_STREAM_HZ

from .audit import fidelity_line
from .common import (
    check_output,
    config_argument,
    console,
    fail,
    plan_or_fail,
    prefix_option,
    prefix_or_fail,
    profile_option,
    rounds_option,
    seed_option,
    window_s_option,
    windows_option,
)


def run_cmd(
    config: str = config_argument(),
    out: Path = typer.Option(..., "--out",
                             help="Run directory: plan.json, pcap/, attacks.jsonl, shaping.jsonl, run.json."),
    seed: int = seed_option("Plan seed."),
    windows: int = windows_option(),
    window_s: float = window_s_option(),
    rounds: int = rounds_option(),
    profile: str = profile_option(),
    prefix: str = prefix_option("Namespace prefix (default: random)."),
    think_s: float = typer.Option(0.5, "--think-s", min=0.0, help="Mean pause between a BS's image fetches."),
    video_kbps: int = typer.Option(None, "--video-kbps", min=1,
                                   help="H.264 bitrate of each UAV's video in kbit/s (payload video, mixed; default "
                                        "500)."),
    mavlink_signing: bool = typer.Option(False, "--mavlink-signing/--no-mavlink-signing",
                                         help="MAVLink 2 message signing between ground stations and UAVs, with a "
                                              "per-run key (payload telemetry, video, mixed)."),
    stream_hz: int = typer.Option(None, "--stream-hz", min=1, max=MAX_STREAM_HZ,
                                  help="Rate (Hz) at which every ground station requests all of its UAVs' telemetry "
                                       "streams, as MAVProxy's streamrate (payload telemetry, video, mixed; default "
                                       f"{DEFAULT_STREAM_HZ}, MAVProxy's). Recorded in plan.json."),
    audit: bool = typer.Option(True, "--audit/--no-audit",
                               help="Audit the run's fidelity at the end (fidelity.json; `uavcas audit` later)."),
) -> None:
    """Realise a scenario's plan on real Linux stacks, attack it, capture every switch."""
    check_output(out, "dir")
    p = plan_or_fail(config, seed, windows, window_s, profile, rounds,
                     **({"stream_hz": stream_hz} if stream_hz is not None else {}))
    for flag, given in (("--stream-hz", stream_hz is not None), ("--mavlink-signing", mavlink_signing)):
        if given and p.scenario is not None and p.scenario.payload not in MAVLINK_PAYLOADS:
            raise fail(f"{flag}: payload {p.scenario.payload!r} carries no MAVLink (use {', '.join(MAVLINK_PAYLOADS)})")
    prefix_or_fail(prefix)

    reason = preflight(p, out)
    if reason:
        raise fail(reason)

    feats, reason = probe_kernel()
    if reason:
        raise fail(reason)


    opts = RunOptions(prefix=prefix, think_mean_s=think_s, mavlink_signing=mavlink_signing,
                      **({"video_kbps": video_kbps} if video_kbps is not None else {}))
    console.print(f"[bold]{p.config}[/] seed={seed}: {len(p.nodes)} nodes, {len(p.windows)} windows x "
                  f"{p.window_s:g} s, shaper {feats.shaper} -> {out}", highlight=False)
    for a in p.attacks:
        console.print(f"  scheduled {a.attack_id}: {','.join(a.attackers) or '(no swarm node)'} -> "
                      f"{','.join(a.victims)} [{a.start_s:.2f}, {a.stop_s:.2f}) s", highlight=False)
    with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed:.0f}/{task.total:.0f}"),
                  TimeElapsedColumn(), console=console, transient=False) as progress:
        task = progress.add_task("setting up", total=len(p.windows))
        t0 = [0.0]

        def on_event(e) -> None:
            if isinstance(e, SetupDone):
                progress.update(task, description=f"setup {e.seconds:.2f} s (prefix {e.prefix})")
            elif isinstance(e, WindowApplied):
                t0[0] = e.t0_unix if e.t0_unix is not None else t0[0]
                progress.update(task, completed=e.window, description=f"window {e.window + 1}/{e.n_windows}")
            elif isinstance(e, AttackLogged) and e.record.event in ("start", "stop"):
                r = e.record
                rel = r.t_unix - t0[0] if t0[0] else 0.0
                more = f" ({r.syn_count} SYNs)" if getattr(r, "syn_count", None) is not None else ""
                if getattr(r, "dropped_frames", None) is not None:
                    more += f" ({r.dropped_frames} frames dropped)"
                progress.console.print(f"  t={rel:6.2f} s  {r.event:5s} {r.attack_id}{more}", highlight=False)
            elif isinstance(e, AttackLogged) and isinstance(e.record, AttackRate):
                r = e.record
                progress.console.print(f"           rate {r.attack_id} {r.attacker}: {r.measured_pps:.0f} pps "
                                       f"(nominal {r.nominal_pps:.0f}, one SYN every {r.hping_interval_us} us)",
                                       highlight=False)
            elif isinstance(e, RunDone):
                progress.update(task, completed=len(p.windows) if e.exit_status == 0 else None,
                                description="done" if e.exit_status == 0 else e.reason)

        started = time.time()
        try:
            art = realize(p, out, opts, on_event=on_event, features=feats)
            if audit and art.exit_status == 0:  # stage 2b: fidelity.json and its summary in run.json
                art.run_info = audit_run(art.out_dir)
        except KeyboardInterrupt:
            raise fail("interrupted; everything the run created was removed", code=130) from None
        except Exception as e:
            raise fail(f"run failed: {type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}", code=1) from None
    info = art.run_info
    console.print(f"{len(art.pcaps)} pcaps, {info.packets_captured if info else 0} packets captured, "
                  f"{info.capture_drops if info else None} dropped; wall {time.time() - started:.1f} s; "
                  f"exit {art.exit_status} ({art.exit_reason})", highlight=False)
    if info is not None and info.fidelity is not None:
        console.print(fidelity_line(info.fidelity), highlight=False)
    if art.exit_status != 0:
        raise typer.Exit(art.exit_status)


def register(app: typer.Typer) -> None:
    app.command("run")(run_cmd)
