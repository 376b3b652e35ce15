"""`uavcas doctor`: kernel features, the chosen shaper, tools, and the two-hop self-test
(`uavcas.diagnostics`), natively or in a VM guest."""

from __future__ import annotations

import json
import os
from pathlib import Path

import typer
from rich.markup import escape
from rich.table import Table

from uavcas.diagnostics import contention, vm
from uavcas.diagnostics.doctor import DoctorResult, run_doctor

from .common import atomic_write_text, check_output, console, fail, one_of, prefix_option, prefix_or_fail

VmAccel = one_of(("auto", "kvm", "tcg"))
HOST_SAMPLE_S = 2.0  # the host's contention, measured before a VM boots
TOOLS_SHOWN = ("nginx", "hping3", "tcpdump", "curl", "wget", "iperf3", "nft", "iptables", "ethtool")


def doctor(
    no_measure: bool = typer.Option(False, "--no-measure", help="Only report features and tools."),
    json_out: Path = typer.Option(None, "--json", help="Also write the result as JSON here."),
    prefix: str = prefix_option("Prefix for the test emulation (default: random)."),
    vm: bool = typer.Option(False, "--vm", help="Run the self-test with the netem backend in a stock Debian kernel "
                                                "under QEMU (this checkout over 9p; ~0.5-3 min)."),
    vm_accel: VmAccel = typer.Option("auto", "--vm-accel",
                                                         help="auto (KVM if it boots, else TCG), kvm or tcg."),
) -> None:
    """Report kernel features, the chosen shaper and tools; measure a two-hop shaped path."""
    if json_out is not None:
        check_output(json_out, "file", "--json")
    prefix_or_fail(prefix)
    if vm:
        return _doctor_vm(vm_accel, json_out)
    if os.geteuid() != 0 and not no_measure:
        raise fail("doctor's measurement needs root (network namespaces); use --no-measure to only report")
    res = run_doctor(prefix, measure=not no_measure)
    f = res.features
    _print_features(f)
    _print_measurement(res)
    if json_out is not None:
        atomic_write_text(json_out, json.dumps(res.to_dict(measured=not no_measure), indent=1) + "\n")
    if f.shaper == "none":
        raise fail("no usable shaper on this kernel (need netem, or htb + nft numgen + NFQUEUE + br_netfilter)")
    if res.error:
        raise fail(f"self-measurement failed: {res.error}", code=1)
    if res.saturated:
        raise fail(f"the CPUs are saturated ({'; '.join(res.contention.reasons)}): emulated timing cannot be "
                   "trusted on this machine now", code=1)
    if not no_measure and not res.ok:
        bad = ", ".join(c.name for c in res.checks if not c.ok)
        raise fail(f"outside tolerance: {bad} (see the table){'; ' + res.warnings[0] if res.warnings else ''}",
                   code=1)
    console.print("[bold green]doctor: ok[/]")


def _doctor_vm(accel: str, json_out: Path | None) -> None:
    if accel not in ("auto", "kvm", "tcg"):
        raise fail(f"--vm-accel: {accel!r} is not one of auto, kvm, tcg")
    why = vm.unavailable()
    if why:
        raise fail(why)
    k = vm.installed()
    console.print(f"guest kernel {k.version} ({k.root}), host root over 9p read-only", highlight=False)
    # An emulated CPU is only as fast as the host lets it be. Sampled before the boot: once
    # running, the guest's own vCPU threads keep the host busy.
    hc = contention.measure(HOST_SAMPLE_S)
    d, run, err = vm.doctor_in_vm(accel, log=lambda s: console.print(f"  {s}", highlight=False))
    busy = f"; the host was {hc.level}: {'; '.join(hc.reasons)}" if hc and hc.level != "quiet" else ""
    if err:
        raise fail(f"VM self-test failed: {err}{busy}", code=1)
    res = DoctorResult.from_dict(d)
    _print_features(res.features)
    _print_measurement(res)
    console.print(f"guest run: {run.accel.upper()}, {run.wall_s:.0f} s from boot to power-off; host CPUs "
                  f"before the boot: {hc.level if hc else 'unknown'}", highlight=False)
    if json_out is not None:
        atomic_write_text(json_out, json.dumps({**res.to_dict(), "vm": {
            "kernel": k.version, "accel": run.accel, "wall_s": round(run.wall_s, 1),
            "host_contention": hc.to_dict() if hc else None}}, indent=1) + "\n")
    if res.error:
        raise fail(f"self-measurement in the guest failed: {res.error}{busy}", code=1)
    if res.backend != "netem":
        raise fail(f"the guest kernel chose the {res.backend} backend, not netem", code=1)
    if not res.ok:
        raise fail(f"outside tolerance in the guest: {', '.join(c.name for c in res.checks if not c.ok)}{busy}",
                   code=1)
    console.print(f"[bold green]doctor --vm: ok[/] (netem backend, kernel {k.version}, {run.accel})", highlight=False)


def _print_features(f) -> None:
    feats = Table(title="kernel features", show_header=True)
    feats.add_column("feature")
    feats.add_column("found")
    for name in ("netns", "netem", "htb", "tbf", "nft", "nft_bridge_numgen", "nfqueue", "br_netfilter"):
        feats.add_row(name, _yes(getattr(f, name)))
    feats.add_row("cgroup cpu", f.cgroup or "[red]none[/]")
    feats.add_row("shaper", f"[bold]{f.shaper}[/]")
    tools = Table(title="tools", show_header=True)
    tools.add_column("tool")
    tools.add_column("path")
    for t in TOOLS_SHOWN:
        tools.add_row(t, f.tools.get(t) or "[red]missing[/]")
    tools.add_row("python scapy", _yes(f.python_scapy))
    console.print(feats)
    console.print(tools)


def _print_measurement(res) -> None:
    if res.checks:
        meas = Table(title=f"two-hop self-measurement (uav0 -> uav1 -> uav2), {res.backend}", show_header=True)
        for col in ("figure", "configured", "expected", "measured", "tolerance", "ok"):
            meas.add_column(col)
        for c in res.checks:
            meas.add_row(f"{c.name} [{c.unit}]", f"{c.configured:.3f}", f"{c.expected:.3f}", f"{c.measured:.3f}",
                         f"[{c.low:.3f}, {c.high:.3f}]", _yes(c.ok))
        console.print(meas)
        if res.retried:
            console.print(f"re-measured once: {', '.join(res.retried)}", highlight=False)
    c = res.contention
    if c is not None:
        psi = "n/a" if c.psi_some_pct is None else f"{c.psi_some_pct:.0f} %"
        console.print(f"CPU contention during the measurement: {c.level} (pressure {psi}, {c.runq_per_cpu:.2f} "
                      f"runnable per CPU, steal {c.steal_pct:.0f} %, timer wake-ups late p50 "
                      f"{c.timer_late_p50_us:.0f} us / p99 {c.timer_late_p99_us:.0f} us)", highlight=False)
    for w in res.warnings:
        console.print(f"[yellow]warning:[/] {escape(w)}", highlight=False)


def _yes(v: bool) -> str:
    return "[green]yes[/]" if v else "[red]no[/]"


def register(app: typer.Typer) -> None:
    app.command("doctor")(doctor)
