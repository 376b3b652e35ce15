"""`uavcas run CONFIG --out DIR`: plan a scenario and realise it in real time on real stacks.

Everything that can be checked without creating anything is checked first (the scenario, root,
tools, namespaces, the output directory); any failure is one line on stderr and exit 2. Then
the kernel is probed (in a throw-away namespace the probe removes) for the shaper backend.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import time
from pathlib import Path

import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn


from .common import console, fail, plan_or_fail

BASE_TOOLS = ("ip", "tc", "bridge", "nft", "iptables", "tcpdump", "nginx", "curl", "timeout", "bash")
RUN_FILES = ("plan.json", "run.json", "attacks.jsonl", "shaping.jsonl")


def preflight(plan, out: Path) -> str | None:
    """The first reason this run cannot start, or None. Creates nothing."""
    if os.geteuid() != 0:
        return "uavcas run needs root (network namespaces, bridges, tc); run it as root"
    if not Path("/proc/self/ns/net").exists():
        return "this kernel has no network namespaces (/proc/self/ns/net is missing)"
    families = {a.family for a in plan.attacks}
    tools = list(BASE_TOOLS) + (["hping3"] if families & {"dos", "ddos"} else [])
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        return f"missing tool(s): {', '.join(missing)}; install them with scripts/setup.sh (as root)"
    if "replay" in families and importlib.util.find_spec("scapy") is None:
        return "replay needs python scapy in this environment (pip install scapy)"
    if out.exists() and not out.is_dir():
        return f"--out {out} exists and is not a directory"
    if out.is_dir() and any(out.iterdir()) and not any((out / f).exists() for f in RUN_FILES):
        return f"--out {out} is not empty and holds no uavcas run; choose an empty or new directory"
    return None


def run_cmd(
    config: str = typer.Argument(..., help="Scenario string, e.g. dos=1000-5-2-image-logdist-adaptive-random-30-95"),
    out: Path = typer.Option(..., "--out", help="Run directory: plan.json, pcap/, attacks.jsonl, shaping.jsonl, run.json."),
    seed: int = typer.Option(0, "--seed", help="Plan seed."),
    windows: int = typer.Option(12, "--windows", min=1, help="Number of windows."),
    window_s: float = typer.Option(5.0, "--window-s", min=0.5, help="Window length in seconds."),
    profile: str = typer.Option(None, "--profile", help="Channel/mobility profile name or JSON path."),
    telemetry: bool = typer.Option(False, "--telemetry", help="Add a 10 Hz MAVLink-like UDP stream per UAV."),
    prefix: str = typer.Option(None, "--prefix", help="Namespace prefix (default: random)."),
    think_s: float = typer.Option(0.5, "--think-s", min=0.0, help="Mean pause between a BS's image fetches."),
) -> None:
    """Realise a scenario's plan on real Linux stacks, attack it, capture every switch."""
    p = plan_or_fail(config, seed, windows, window_s, profile)
    if prefix is not None:
        from uavcas.emulation.naming import check_prefix

        try:
            check_prefix(prefix)
        except ValueError as e:
            raise fail(f"--prefix: {e}") from None
    reason = preflight(p, out)
    if reason:
        raise fail(reason)
    from uavcas.emulation.probe import probe

    feats = probe()
    if not feats.netns:
        raise fail("cannot create network namespaces here (ip netns add failed)")
    if feats.shaper == "none":
        raise fail("no usable shaper on this kernel (need netem, or htb + nft numgen + NFQUEUE); see `uavcas doctor`")

    from uavcas.emulation.runner import RunOptions, realize

    opts = RunOptions(prefix=prefix, telemetry=telemetry, think_mean_s=think_s)
    console.print(f"[bold]{p.config}[/] seed={seed}: {len(p.nodes)} nodes, {len(p.windows)} windows x "
                  f"{p.window_s:g} s, shaper {feats.shaper} -> {out}", highlight=False)
    for a in p.attacks:
        console.print(f"  scheduled {a.attack_id}: {','.join(a.attackers)} -> {','.join(a.victims)} "
                      f"[{a.start_s:.2f}, {a.stop_s:.2f}) s", highlight=False)
    with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed:.0f}/{task.total:.0f}"),
                  TimeElapsedColumn(), console=console, transient=False) as progress:
        task = progress.add_task("setting up", total=len(p.windows))
        t0 = [0.0]

        def on_event(e: dict) -> None:
            kind = e.get("kind")
            if kind == "setup":
                progress.update(task, description=f"setup {e['seconds']:.2f} s (prefix {e['prefix']})")
            elif kind == "window":
                t0[0] = e.get("t0_unix", t0[0])
                progress.update(task, completed=e["window"],
                                description=f"window {e['window'] + 1}/{e['n_windows']}")
            elif kind == "attack" and e.get("event") in ("start", "stop"):
                rel = e["t_unix"] - t0[0] if t0[0] else 0.0
                more = f" ({e['syn_count']} SYNs)" if "syn_count" in e else ""
                more += f" ({e['dropped_frames']} frames dropped)" if "dropped_frames" in e else ""
                progress.console.print(f"  t={rel:6.2f} s  {e['event']:5s} {e['attack_id']}{more}", highlight=False)
            elif kind == "attack" and e.get("event") == "rate":
                progress.console.print(f"           rate {e['attack_id']} {e['attacker']}: {e['measured_pps']:.0f} pps "
                                       f"(nominal {e['nominal_pps']:.0f}, hping3 -i u{e['hping_interval_us']})",
                                       highlight=False)
            elif kind == "done":
                progress.update(task, completed=len(p.windows) if e["exit_status"] == 0 else None,
                                description="done" if e["exit_status"] == 0 else e["reason"])

        started = time.time()
        try:
            art = realize(p, out, opts, on_event=on_event, features=feats)
        except KeyboardInterrupt:
            raise fail("interrupted; everything the run created was removed", code=130) from None
        except Exception as e:
            raise fail(f"run failed: {type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}", code=1) from None
    info = art.run_info
    console.print(f"{len(art.pcaps)} pcaps, {info.get('packets_captured', 0)} packets captured, "
                  f"{info.get('capture_drops')} dropped; wall {time.time() - started:.1f} s; "
                  f"exit {art.exit_status} ({art.exit_reason})", highlight=False)
    if art.exit_status != 0:
        raise typer.Exit(art.exit_status)


def register(app: typer.Typer) -> None:
    app.command("run")(run_cmd)
