"""What the kernel holds of a run's shaping, read back: HTB classes (rate and burst) and the nft
loss rules, with tc's rate and size notations parsed. The shapers compare it with what they
asked for (`shaping.Shaper.readback`), and the audit's model uses the burst the kernel held.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence

from . import kernel
from .counters import NFT_TABLE

_UNIT = {"bit": 1, "kbit": 1e3, "mbit": 1e6, "gbit": 1e9, "tbit": 1e12}


def parse_tc_rate(text: str) -> float:
    """'9600Kbit' -> Mbit/s."""
    m = re.fullmatch(r"([\d.]+)([KMGT]?bit)", text, re.IGNORECASE)
    if not m:
        raise ValueError(f"unparsable tc rate {text!r}")
    return float(m.group(1)) * _UNIT[m.group(2).lower()] / 1e6


def parse_tc_size(text: str) -> int:
    """'4800b' / '9Kb' (tc's sizes: bytes, binary multiples) -> bytes."""
    m = re.fullmatch(r"([\d.]+)([KMG]?)b", text)
    if not m:
        raise ValueError(f"unparsable tc size {text!r}")
    return round(float(m.group(1)) * {"": 1, "K": 1024, "M": 1024**2, "G": 1024**3}[m.group(2)])


def read_htb_classes(fabric_ns: str, ports: Sequence[str]) -> dict[str, tuple[float, int]]:
    """(rate in Mbit/s, burst in bytes) of class 1:1 per port (`tc -j class show` has no JSON for
    htb in iproute2 6.1)."""
    if not ports:
        return {}
    out = kernel.run(["tc", "-n", fabric_ns, "-batch", "-"],
                     input_text="".join(f"class show dev {p}\n" for p in ports)).stdout
    got = [(parse_tc_rate(m.group(1)), parse_tc_size(m.group(2)))
           for m in re.finditer(r"class htb 1:1 .*?\brate (\S+) .*?\bburst (\S+)", out)]
    if len(got) != len(ports):
        raise kernel.KernelError(f"htb readback: {len(got)} classes for {len(ports)} ports")
    return dict(zip(ports, got))


def read_nft_losses(fabric_ns: str, table: str = NFT_TABLE) -> dict[str, float]:
    """Loss per port as the kernel holds it (ports without a drop rule: 0)."""
    out = kernel.run(["ip", "netns", "exec", fabric_ns, "nft", "-j", "list", "table", "bridge", table]).stdout
    losses: dict[str, float] = {}
    for item in json.loads(out)["nftables"]:
        if "chain" in item and item["chain"]["name"].startswith("p_"):
            losses.setdefault(item["chain"]["name"][2:].replace("_", "-"), 0.0)
        rule = item.get("rule")
        if not rule or not rule["chain"].startswith("p_"):
            continue
        port = rule["chain"][2:].replace("_", "-")
        matches = [e["match"] for e in rule["expr"] if isinstance(e, dict) and "match" in e]
        has_drop = any(isinstance(e, dict) and "drop" in e for e in rule["expr"])
        for match in matches:
            if isinstance(match.get("left"), dict) and "numgen" in match["left"]:
                losses[port] = match["right"] / match["left"]["numgen"]["mod"]
        if has_drop and not matches:  # an unconditional drop: the loss-1.0 rule
            losses[port] = 1.0
    return losses
