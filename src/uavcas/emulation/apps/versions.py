"""Versions of the external tools a run used (for run.json), asked once per process."""

from __future__ import annotations

import functools
import re
import shutil
import subprocess

# tool -> (argv, regex for the version in stdout+stderr)
QUERIES = {
    "nginx": (["nginx", "-v"], r"nginx/(\S+)"),
    "hping3": (["hping3", "-v"], r"version (\S+)"),
    "tcpdump": (["tcpdump", "--version"], r"tcpdump version (\S+)"),
    "libpcap": (["tcpdump", "--version"], r"libpcap version (\S+)"),
    "curl": (["curl", "--version"], r"curl (\S+)"),
    "iproute2": (["ip", "-V"], r"iproute2-([\w.]+)|version ([\w.]+)"),
    "nft": (["nft", "--version"], r"v(\S+)"),
    "iptables": (["iptables", "--version"], r"v(\S+)"),
    "ffmpeg": (["ffmpeg", "-version"], r"ffmpeg version (\S+)"),
}


@functools.lru_cache(maxsize=1)
def tool_versions() -> dict[str, str | None]:
    out: dict[str, str | None] = {}
    for tool, (argv, pattern) in QUERIES.items():
        if shutil.which(argv[0]) is None:
            out[tool] = None
            continue
        try:
            p = subprocess.run(["timeout", "5", *argv], capture_output=True, text=True)
            m = re.search(pattern, p.stdout + p.stderr)
            out[tool] = next((g for g in m.groups() if g), None) if m else None
        except OSError:
            out[tool] = None
    return out
