"""Everything that can be checked before a run creates anything: root, namespaces, tools, OUT."""

from __future__ import annotations

import importlib.util
import os
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from uavcas.attacks import family
from uavcas.rundir import RunDir

if TYPE_CHECKING:
    from uavcas.twin.model import Plan

BASE_TOOLS = ("ip", "tc", "bridge", "nft", "iptables", "tcpdump", "nginx", "curl", "timeout", "bash")


def preflight(plan: "Plan", out: Path) -> str | None:
    """The first reason this run cannot start, or None. Creates nothing."""
    if os.geteuid() != 0:
        return "uavcas run needs root (network namespaces, bridges, tc); run it as root"
    if not Path("/proc/self/ns/net").exists():
        return "this kernel has no network namespaces (/proc/self/ns/net is missing)"
    fams = [family(f) for f in dict.fromkeys(a.family for a in plan.attacks)]
    tools = list(dict.fromkeys([*BASE_TOOLS, *(t for f in fams for t in f.tools)]))
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        return f"missing tool(s): {', '.join(missing)}; install them with scripts/setup.sh (as root)"
    for f in fams:
        for mod in f.python_modules:
            if importlib.util.find_spec(mod) is None:
                return f"{f.name} needs python {mod} in this environment (pip install {mod})"
    if out.exists() and not out.is_dir():
        return f"--out {out} exists and is not a directory"
    if out.is_dir() and any(out.iterdir()) and not RunDir(out).holds_run():
        return f"--out {out} is not empty and holds no uavcas run; choose an empty or new directory"
    return None


def probe_kernel(features=None):
    """(kernel features, the reason a run cannot use them or None); probes in a throw-away netns."""
    if features is None:
        from .probe import probe

        features = probe()
    if not features.netns:
        return features, "cannot create network namespaces here (ip netns add failed)"
    if features.shaper == "none":
        return features, ("no usable shaper on this kernel (need netem, or htb + nft numgen + NFQUEUE); "
                          "see `uavcas doctor`")
    return features, None
