"""What this kernel and machine offer, found by *trying* (not by reading config files).

Each qdisc/nft/iptables feature is tried in a throw-away namespace so a module that autoloads
counts as present and nothing touches the root namespace. The result picks the shaper backend.
"""

from __future__ import annotations

import functools
import importlib.util
import os
import shutil
import subprocess
from dataclasses import asdict, dataclass, field
from pathlib import Path

from uavcas.network.naming import new_prefix

from . import kernel

CGROUP_ROOT = Path("/sys/fs/cgroup")


@dataclass(frozen=True)
class Features:
    root: bool
    netns: bool
    netem: bool
    htb: bool
    tbf: bool
    nft: bool
    nft_bridge_numgen: bool
    nfqueue: bool  # iptables NFQUEUE target + physdev match, usable via br_netfilter
    br_netfilter: bool
    cgroup: str | None  # "v2", "v1" or None (cpu controller available for a CPU cap)
    tools: dict[str, str | None] = field(default_factory=dict)  # tool -> path (None: missing)
    python_scapy: bool = False

    @property
    def shaper(self) -> str:
        """The backend `make_shaper` will choose."""
        if self.netem and self.htb:
            return "netem"
        if self.htb and self.nft_bridge_numgen and self.nfqueue and self.br_netfilter:
            return "htb-nft-nfqueue"
        return "none"

    def to_dict(self) -> dict:
        d = asdict(self)
        d["shaper"] = self.shaper
        return d


TOOLS = ("ip", "tc", "bridge", "nft", "iptables", "ethtool", "tcpdump", "nginx", "hping3", "curl",
         "wget", "iperf3", "ping", "timeout")


def cgroup_version() -> str | None:
    if (CGROUP_ROOT / "cgroup.controllers").exists():
        ctrls = (CGROUP_ROOT / "cgroup.controllers").read_text().split()
        return "v2" if "cpu" in ctrls else None
    if (CGROUP_ROOT / "cpu" / "cpu.cfs_quota_us").exists():
        return "v1"
    return None


def _try(argv: list[str], input_text: str | None = None) -> bool:
    try:
        return kernel.run(argv, input_text=input_text, check=False, timeout_s=5).returncode == 0
    except (OSError, subprocess.SubprocessError):
        return False


@functools.lru_cache(maxsize=1)
def probe() -> Features:
    tools = {t: shutil.which(t) for t in TOOLS}
    scapy = importlib.util.find_spec("scapy") is not None
    root = os.geteuid() == 0
    if not (root and tools["ip"] and Path("/proc/self/ns/net").exists()):
        return Features(root, False, False, False, False, False, False, False, False,
                        cgroup_version(), tools, scapy)
    ns = f"{new_prefix()}-probe"
    try:
        if not _try(["ip", "netns", "add", ns]):
            return Features(root, False, False, False, False, False, False, False, False,
                            cgroup_version(), tools, scapy)
        kernel.write_sysctls(ns, {"net.ipv6.conf.all.disable_ipv6": 1, "net.ipv6.conf.default.disable_ipv6": 1})
        kernel.run_batch("ip", ns, [f"link add p{k} type veth peer name q{k}" for k in range(3)])
        tc = ["tc", "-n", ns, "qdisc", "add", "dev"]
        netem = _try(tc + ["p0", "root", "netem", "delay", "1ms"])
        htb = _try(tc + ["p1", "root", "handle", "1:", "htb", "default", "1"])
        tbf = _try(tc + ["p2", "root", "tbf", "rate", "1mbit", "burst", "15k", "latency", "50ms"])
        nft = bool(tools["nft"]) and _try(["ip", "netns", "exec", ns, "nft", "list", "tables"])
        numgen = nft and _try(["ip", "netns", "exec", ns, "nft", "-f", "-"],
                              "table bridge t {\n chain c {\n  type filter hook forward priority 0;\n"
                              "  numgen random mod 1000 < 10 drop\n }\n}\n")
        brnf = _try(["ip", "netns", "exec", ns, "test", "-e", "/proc/sys/net/bridge/bridge-nf-call-iptables"])
        nfq = bool(tools["iptables"]) and _try(
            ["ip", "netns", "exec", ns, "iptables", "-A", "FORWARD", "-m", "physdev", "--physdev-out", "p0",
             "-j", "NFQUEUE", "--queue-num", "0", "--queue-bypass"])
        return Features(root, True, netem, htb, tbf, nft, numgen, nfq, brnf, cgroup_version(), tools, scapy)
    finally:
        _try(["ip", "netns", "del", ns])
