"""One-line meanings of CICFlowMeter-style column names ("Fwd IAT Mean", "Flow Bytes/s", ...),
worded for a standard by what it measures (`Wording`). Both shipped standards name their columns
this way; a standard with other names writes its meanings itself."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

_STAT = {"Mean": "mean", "Std": "standard deviation", "Max": "largest", "Min": "smallest", "Total": "sum",
         "Variance": "variance"}
_OTHER = {
    "Flow Duration": "last packet time - first packet time",
    "Down/Up Ratio": "backward packets / forward packets, integer division (0 without forward packets)",
    "Active Mean": "mean length of the active periods (between idle gaps over 5 s)",
    "Idle Mean": "mean of the idle gaps over 5 s", "Idle Max": "largest idle gap over 5 s",
}  # fmt: skip


@dataclass(frozen=True)
class Wording:
    """What a standard's words measure."""

    length: str  # a packet's length, e.g. "frame length"
    forward: str  # which packets are forward, e.g. "forward (initiator -> responder)"
    header: str  # meaning of Fwd/Bwd Header Length; "{who}" is replaced by the packets meant
    zero_duration: str  # what a rate over a flow of duration 0 is
    cwe_flag: str = "CWR"  # the flag "CWE Flag Count" counts (CICFlowMeter: CWR)
    ece_flag: str = "ECE"  # the flag "ECE Flag Count" counts


def _meaning(name: str, w: Wording) -> str:
    words = name.replace("Backward", "Bwd").split()
    who = (f"{w.forward} packets" if "Fwd" in words else "backward packets" if "Bwd" in words
           else "packets of both directions")
    if "IAT" in words:
        return f"{_STAT[words[-1]]} of the gaps between consecutive {who}"
    if name.endswith("Flag Count"):
        return f"packets with the {({'CWE': w.cwe_flag, 'ECE': w.ece_flag}).get(words[0], words[0])} flag set"
    if "Header" in words:
        return w.header.format(who=who)
    if name in ("Min Packet Length", "Max Packet Length"):
        return f"{_STAT[words[0]]} {w.length} of all packets"
    if "Packet Length" in name:
        return f"{_STAT[words[-1]]} of the {w.length} of {who}"
    if name.startswith("Total Length of"):
        return f"sum of the {w.length} of {who}"
    if name.startswith("Total"):
        return f"number of {who}"
    if name.endswith("/s"):
        what = (f"{w.length} summed over all packets per second of Flow Duration" if "Bytes" in name
                else f"number of {who} per second of Flow Duration")
        return f"{what} (0-duration flows: {w.zero_duration})"
    if name == "Average Packet Size":
        return f"sum of the {w.length} / number of packets"
    return _OTHER[name]


def meanings(columns: Iterable[str], wording: Wording) -> dict[str, str]:
    """column -> its one-line meaning; a name outside the CICFlowMeter grammar is a KeyError."""
    return {c: _meaning(c, wording) for c in columns}
