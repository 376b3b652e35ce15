"""Emulated hosts: one network namespace per UAV/BS, each a lightweight container.

A host has its own loopback, one interface `eth0` (the far end of a veth whose other end is a
port of its switch in the fabric namespace), the plan's IP and MAC, a static ARP table for every
other node (no ARP broadcast ever needs flooding), IPv6 off (no DAD/RS/MLD chatter) and TSO/GSO/
GRO off (shaping then acts on real, MTU-sized frames). Optionally a CPU cap through a cgroup
(v2 `cpu.max` or v1 `cpu.cfs_quota_us`, whichever the host has).

`ip netns exec` remounts /sys, hiding /sys/fs/cgroup, so a capped process joins its cgroup
*before* it enters the namespace (a tiny `sh` that writes `$$` and execs).
"""

from __future__ import annotations

import ipaddress
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from uavcas.network.naming import Naming

from . import kernel
from .probe import CGROUP_ROOT

IPV6_OFF = {"net.ipv6.conf.all.disable_ipv6": 1, "net.ipv6.conf.default.disable_ipv6": 1,
            "net.ipv6.conf.lo.disable_ipv6": 1}


@dataclass(frozen=True)
class HostSpec:
    name: str
    index: int
    ip: str
    mac: str
    ns: str


def subnet_prefixlen(ips: Sequence[str]) -> int:
    """Smallest common prefix of all node addresses (at most /24, at least /8): one L2 segment."""
    addrs = [int(ipaddress.IPv4Address(ip)) for ip in ips]
    for plen in range(24, 7, -1):
        mask = (0xFFFFFFFF << (32 - plen)) & 0xFFFFFFFF
        if len({a & mask for a in addrs}) == 1:
            return plen
    raise ValueError("node addresses share no /8")


def host_lines(me: HostSpec, everyone: Sequence[HostSpec], plen: int) -> list[str]:
    """`ip -batch` lines configuring one host (run inside its namespace)."""
    lines = ["link set lo up", f"addr add {me.ip}/{plen} dev {Naming.HOST_IF}"]
    lines += [f"neigh replace {o.ip} lladdr {o.mac} dev {Naming.HOST_IF} nud permanent"
              for o in everyone if o.name != me.name]
    lines.append(f"link set {Naming.HOST_IF} up")
    return lines


class CpuCaps:
    """Per-node CPU caps in cgroup v2 or v1 under `uavcas.<prefix>`."""

    def __init__(self, naming: Naming, version: str | None) -> None:
        self.version = version
        if version == "v2":
            self.base = CGROUP_ROOT / naming.cgroup_dir_name
        elif version == "v1":
            self.base = CGROUP_ROOT / "cpu" / naming.cgroup_dir_name
        else:
            self.base = None
        self.paths: dict[str, Path] = {}

    def planned_dirs(self, nodes: Sequence[str]) -> list[str]:
        if self.base is None:
            return []
        return [str(self.base / n) for n in nodes] + [str(self.base)]

    def create(self, node: str, cpus: float, period_us: int = 100_000) -> Path:
        if self.base is None:
            raise kernel.KernelError("no cgroup cpu controller (v1 or v2) for a CPU cap")
        quota = max(1000, round(cpus * period_us))
        path = self.base / node
        if self.version == "v2":
            ctl = CGROUP_ROOT / "cgroup.subtree_control"
            if "cpu" not in ctl.read_text().split():
                ctl.write_text("+cpu")
            self.base.mkdir(exist_ok=True)
            (self.base / "cgroup.subtree_control").write_text("+cpu")
            path.mkdir(exist_ok=True)
            (path / "cpu.max").write_text(f"{quota} {period_us}")
        else:
            path.mkdir(parents=True, exist_ok=True)
            (path / "cpu.cfs_period_us").write_text(str(period_us))
            (path / "cpu.cfs_quota_us").write_text(str(quota))
        self.paths[node] = path
        return path

    def procs_file(self, node: str) -> Path | None:
        path = self.paths.get(node)
        return None if path is None else path / "cgroup.procs"


def node_argv(ns: str, argv: Sequence[str], procs_file: Path | None = None,
              timeout_s: float | None = None) -> list[str]:
    """The command line that runs argv inside namespace ns (and cgroup), optionally time-boxed."""
    inner = ["ip", "netns", "exec", ns, *argv]
    if timeout_s is not None:
        inner = kernel.timed(inner, timeout_s)
    if procs_file is not None:
        inner = ["sh", "-c", 'echo $$ > "$0" && exec "$@"', str(procs_file), *inner]
    return inner


class Hosts:
    def __init__(self, naming: Naming, specs: Sequence[HostSpec], cgroup_version: str | None) -> None:
        self.naming = naming
        self.specs = {s.name: s for s in specs}
        self.caps = CpuCaps(naming, cgroup_version)

    @property
    def namespaces(self) -> list[str]:
        return [s.ns for s in self.specs.values()]

    def configure(self) -> None:
        """After the fabric created each `eth0`: sysctls, offloads, addresses, static ARP, up."""
        specs = list(self.specs.values())
        for s in specs:
            kernel.offloads_off(s.ns, Naming.HOST_IF)
        plen = subnet_prefixlen([s.ip for s in specs])
        kernel.run_batches([kernel.Batch("ip", s.ns, host_lines(s, specs, plen)) for s in specs])

    def cap_cpu(self, cpus: float, nodes: Sequence[str] | None = None) -> None:
        for n in nodes or list(self.specs):
            self.caps.create(n, cpus)

    def argv(self, node: str, argv: Sequence[str], timeout_s: float | None = None) -> list[str]:
        return node_argv(self.specs[node].ns, argv, self.caps.procs_file(node), timeout_s)

    def popen(self, node: str, argv: Sequence[str], timeout_s: float | None = None, **kw) -> subprocess.Popen:
        return subprocess.Popen(self.argv(node, argv, timeout_s), **kw)

    def run(self, node: str, argv: Sequence[str], timeout_s: float = 30.0, **kw) -> subprocess.CompletedProcess:
        kw.setdefault("capture_output", True)
        kw.setdefault("text", True)
        return subprocess.run(self.argv(node, argv, timeout_s), **kw)
