"""Everything that can be checked before a run creates anything: root, namespaces, tools, OUT.

The output directory rule (a run never deletes what it did not create): `--out` must be absent,
empty, or hold a uavcas run that is over, finished or killed (run.json, or the `.uavcas-run`
marker a run writes first), of one prefix, whose prefix no live run holds. Reusing it removes
only what a run writes there (`prepare_out_dir`); any other file stays.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import time
from pathlib import Path
from typing import TYPE_CHECKING

from uavcas.attacks import family
from uavcas.rundir import CAPTURE_SUFFIXES, RunDir, RunDirError, RunOwner

from .cleanup import is_live
from .probe import probe

if TYPE_CHECKING:
    from uavcas.twin.model import Plan

BASE_TOOLS = ("ip", "tc", "bridge", "nft", "iptables", "tcpdump", "nginx", "curl", "timeout", "bash")


def preflight(plan: "Plan", out: Path) -> str | None:
    """The first reason this run cannot start, or None. Creates nothing."""
    if os.geteuid() != 0:
        return "uavcas run needs root (network namespaces, bridges, tc); run it as root"
    if not Path("/proc/self/ns/net").exists():
        return "this kernel has no network namespaces (/proc/self/ns/net is missing)"
    problem = out_dir_problem(out)  # the user's own argument first
    if problem:
        return problem
    fams = [family(f) for f in dict.fromkeys(a.family for a in plan.attacks)]
    tools = list(dict.fromkeys([*BASE_TOOLS, *(t for f in fams for t in f.tools)]))
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        return f"missing tool(s): {', '.join(missing)}; install them with scripts/setup.sh (as root)"
    for f in fams:
        for mod in f.python_modules:
            if importlib.util.find_spec(mod) is None:
                return f"{f.name} needs python {mod} in this environment (pip install {mod})"
    return None


def out_dir_problem(out: Path) -> str | None:
    """Why a run cannot write into `out` (see the module docstring), or None."""
    if out.exists() and not out.is_dir():
        return f"--out {out} exists and is not a directory"
    if not out.is_dir() or not any(out.iterdir()):
        return None
    rd = RunDir(out)
    try:
        info, owner = rd.read_info(), rd.read_owner()
    except RunDirError as e:
        return f"--out {out} is not empty and holds no readable uavcas run ({e}); choose an empty or new directory"
    if info is None and owner is None:
        return f"--out {out} is not empty and holds no uavcas run; choose an empty or new directory"
    prefixes = sorted({p for p in (info.prefix if info else None, owner.prefix if owner else None) if p})
    if len(prefixes) > 1:
        return f"--out {out} holds files of two runs (prefixes {', '.join(prefixes)}); choose another directory"

    if prefixes and is_live(prefixes[0]):
        return f"--out {out} belongs to a live run (prefix {prefixes[0]}); choose another directory"
    return None


def prepare_out_dir(out: Path, prefix: str) -> None:
    """Make `out` ready for the run with this prefix: claim it (the marker first), then remove
    what an earlier run wrote there, and nothing else. Raises RunDirError when it may not."""
    problem = out_dir_problem(out)
    if problem:
        raise RunDirError(problem)
    rd = RunDir(out)
    out.mkdir(parents=True, exist_ok=True)
    rd.write_owner(RunOwner(prefix=prefix, pid=os.getpid(), started_unix=time.time()))
    for f in rd.files():
        f.unlink(missing_ok=True)
    if rd.pcap_dir.is_dir():
        for f in rd.pcap_dir.iterdir():
            if f.is_file() and f.suffix in CAPTURE_SUFFIXES:
                f.unlink()
    shutil.rmtree(rd.logs_dir, ignore_errors=True)  # tool logs: a run copies them there whole
    rd.pcap_dir.mkdir(exist_ok=True)


def probe_kernel(features=None):
    """(kernel features, the reason a run cannot use them or None); probes in a throw-away netns."""
    if features is None:
        features = probe()
    if not features.netns:
        return features, "cannot create network namespaces here (ip netns add failed)"
    if features.shaper == "none":
        return features, ("no usable shaper on this kernel (need netem, or htb + nft numgen + NFQUEUE); "
                          "see `uavcas doctor`")
    return features, None
