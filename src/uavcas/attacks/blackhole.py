"""Blackhole: the victim's traffic vanishes at its own switch while the attack lasts.

- token `blackhole` (no parameters);
- schedule: the 'attacker' is the compromised relay credited with the drop, the victim's first
  hop towards its BS at t = 0 when that is a UAV (else any other UAV);
- executor: an nft *bridge* table on the victim's switch drops the victim's IPv4 frames on every
  port of that switch, in both directions (ip saddr = victim and ip daddr = victim). ARP is
  another ethertype and is never matched, so neighbours keep resolving; other nodes' transit
  through the same switch is untouched. Priority -20: before the shaper's loss table (-10) and
  before br_netfilter hands frames to iptables/NFQUEUE (0), so dropped frames cost no delay
  work. One atomic `nft -f`; at stop its drop count is logged and its rules are flushed, the
  table and its empty chain staying (deleting a base chain unregisters a netfilter hook, and the
  kernel then drops every frame the delay stage holds in the namespace's NFQUEUE, frames whose
  link time its pacer had charged). The start is logged once the table is in force and the stop
  just before its rules go, so [start, stop) is exactly when the drop held;
- truth (effect `blackhole`, label source "blackhole-drops"): a packet to or from a victim whose
  transmission was last seen at the victim's switch, at a time inside [start, stop): the rule
  dropped it there (seen before the victim's switch and not after it). Its other observations,
  upstream, carry the same effect;
- provoked: nothing (the default hook). What a drop leads to, the peers' retransmissions, is
  sent to the victim again and judged by the drop rule itself.
"""

from __future__ import annotations

import json
import re
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from uavcas.emulation import kernel
from uavcas.network.naming import Naming
from uavcas.scenario_model import SpecBase

from .base import AttackExecutor, AttackFamily, ScheduleDraw, SyntheticPackets, TruthContext
from .registry import register

if TYPE_CHECKING:  # types only: the twin's and labels' package __init__s load this registry
    from uavcas.labels.attacklog import AttackWindow
    from uavcas.twin.model import Attack


class BlackholeSpec(SpecBase):
    family: Literal["blackhole"] = "blackhole"


def table_name(attack_id: str) -> str:
    return "uavcas_bh_" + re.sub(r"[^A-Za-z0-9_]", "_", attack_id)


def ruleset(table: str, ports: list[str], victim_ip: str) -> str:
    ifs = ", ".join(f'"{p}"' for p in sorted(ports))
    return (f"table bridge {table} {{\n"
            f"  chain fw {{ type filter hook forward priority -20; policy accept;\n"
            f"    iifname {{ {ifs} }} ether type ip ip saddr {victim_ip} counter drop\n"
            f"    iifname {{ {ifs} }} ether type ip ip daddr {victim_ip} counter drop\n"
            f"  }}\n}}\n")


def drop_on(fabric_ns: str, table: str, ports: list[str], victim_ip: str) -> None:
    kernel.run(["ip", "netns", "exec", fabric_ns, "nft", "-f", "-"], input_text=ruleset(table, ports, victim_ip))


def drop_off(fabric_ns: str, table: str) -> int:
    """Flush the table's rules (the table and its base chain stay: module docstring); returns how
    many frames it dropped (both rules)."""
    dropped = 0
    r = kernel.run(["ip", "netns", "exec", fabric_ns, "nft", "-j", "list", "table", "bridge", table], check=False)
    if r.returncode == 0:
        for item in json.loads(r.stdout).get("nftables", []):
            for expr in item.get("rule", {}).get("expr", []):
                if isinstance(expr, dict) and "counter" in expr:
                    dropped += int(expr["counter"].get("packets", 0))
        kernel.run(["ip", "netns", "exec", fabric_ns, "nft", "flush", "chain", "bridge", table, "fw"])
    return dropped


def switch_ports(index: int) -> list[str]:
    """The victim switch's host port and (by wildcard) every link port it has or will get."""
    return [Naming.host_port(index), Naming.link_port(index, 0).rsplit("-", 1)[0] + "-*"]


@register
class Blackhole(AttackFamily):
    name = "blackhole"
    spec = BlackholeSpec
    usage = "blackhole"
    truth_rule = ("a packet to or from the victim last seen at the victim's switch inside [start, stop) "
                  "(dropped there)")
    provoked_rule = "nothing (a peer's retransmission is dropped again, or reaches the victim after the stop)"
    tools = ("nft",)

    def attackers(self, spec: SpecBase, draw: ScheduleDraw) -> list[str]:
        route = draw.routes_start.get(draw.victim, [])
        relay = route[1] if len(route) > 1 else None
        if relay in draw.pool and relay not in draw.used:
            draw.used.add(relay)
            return [relay]
        return draw.take(1)

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        for v in attack.victims:
            drop_on(ex.emu.fabric_ns, table_name(attack.attack_id), switch_ports(ex.index(v)), ex.ip(v))
        # logged when the rule is in force (nft -f returns after the kernel committed it)
        return {"t_unix": ex.now(), "switch": [ex.emu.switch(v).bridge for v in attack.victims]}

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        t = ex.now()  # logged while the rule still holds: replies after it are not blackholed
        return {"t_unix": t, "dropped_frames": drop_off(ex.emu.fabric_ns, table_name(attack.attack_id))}

    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        hit = np.zeros(ctx.n, dtype=bool)
        for w in windows:
            at = ctx.at_switch_of(ctx.node_names(w.victim_ips)) & ctx.is_last
            hit |= at & ctx.during(w.start_unix, w.stop_unix) & ctx.touching(w.victim_ips)
        return ctx.spread(hit)

    def synthetic_change(self, rng: np.random.Generator, packets: SyntheticPackets, made: bool) -> SyntheticPackets:
        """Benign-like but for the victim's answers: 80 % of the backward packets dropped (all of them
        when another family made the flow: nothing of the victim comes back), the gaps stretched by
        the retransmission timeouts."""
        t, size, d, flags = packets
        m = (d == 0) | (rng.random(len(t)) < (0.0 if made else 0.2))
        m[0] = True
        return t[m] * 1.3, size[m], d[m], flags[m]
