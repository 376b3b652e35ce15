"""A port's kernel counters: what its rate stage sent, and what the queue, the loss rule and the
port itself dropped (read by `Shaper.counters`, logged per window by `sampling.WindowSampler`).

The loss rule counts into a *named* nft counter per port (`shaping.nft_counter`), which
survives the per-window rewrite of the port's rule; qdisc counters survive `tc ... change`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

from . import kernel

NFT_TABLE = "uavcas_shape"  # the shaper's nft table (its loss rules and their counters)


@dataclass(frozen=True)
class PortCounters:
    """Cumulative kernel counters of one port (None: the backend has no such counter)."""

    sent_packets: int | None
    queue_drops: int | None
    loss_drops: int | None
    link_drops: int | None = None  # dropped on transmit by the port itself (no queue attached yet, peer down)
    # admitted and charged by the delay stage's pacer (fallback backend): against `sent_packets`,
    # frames the pacer charged link time for that never left the port
    paced_packets: int | None = None


def read_link_drops(fabric_ns: str) -> dict[str, int]:
    """Transmit drops of every interface of the namespace (`ip -s link`)."""
    out = json.loads(kernel.run(["ip", "-n", fabric_ns, "-s", "-j", "link", "show"]).stdout or "[]")
    return {d["ifname"]: int(d.get("stats64", {}).get("tx", {}).get("dropped", 0)) for d in out if "ifname" in d}


def read_qdisc_counters(fabric_ns: str) -> dict[str, dict[str, dict]]:
    """`tc -s qdisc` of the namespace: port -> qdisc kind -> its statistics."""
    out: dict[str, dict[str, dict]] = {}
    for q in json.loads(kernel.run(["tc", "-n", fabric_ns, "-s", "-j", "qdisc", "show"]).stdout or "[]"):
        out.setdefault(q.get("dev", ""), {})[q.get("kind", "")] = q
    return out


def read_nft_counters(fabric_ns: str, table: str = NFT_TABLE) -> dict[str, int]:
    """Packets counted by each port's named loss counter (ports by name)."""
    out = kernel.run(["ip", "netns", "exec", fabric_ns, "nft", "-j", "list", "counters", "table", "bridge", table],
                     check=False).stdout
    counts = {}
    for item in json.loads(out or "{}").get("nftables", []):
        c = item.get("counter")
        if c and c.get("name", "").startswith("c_"):
            counts[c["name"][2:].replace("_", "-")] = int(c.get("packets", 0))
    return counts
