"""Fabric-side rules the attacks need, issued in the run's fabric namespace by port name.

These sit here (not in the emulation core) because only the attacks use them; each is one
atomic `nft -f` or one `tc -batch`, undone by deleting exactly what it added.

* Blackhole: an nft *bridge* table dropping the victim's IPv4 frames on every port of the
  victim's switch, in both directions (ip saddr = victim and ip daddr = victim). ARP is another
  ethertype and is never matched, so neighbours keep resolving; other nodes' transit through
  the same switch is untouched. Priority -20: before the shaper's loss table (-10) and before
  br_netfilter hands frames to iptables/NFQUEUE (0), so dropped frames cost no delay work.
* Mirror (replay): act_mirred copies every IPv4 frame the victim sends (ingress of its host
  port) and receives (egress of its host port) out of the attacker's host port, so the
  attacker's `eth0` sees the victim's traffic wherever the attacker is.
"""

from __future__ import annotations

import json
import re

from uavcas.emulation import kernel


def blackhole_table(attack_id: str) -> str:
    return "uavcas_bh_" + re.sub(r"[^A-Za-z0-9_]", "_", attack_id)


def blackhole_ruleset(table: str, ports: list[str], victim_ip: str) -> str:
    ifs = ", ".join(f'"{p}"' for p in sorted(ports))
    return (f"table bridge {table} {{\n"
            f"  chain fw {{ type filter hook forward priority -20; policy accept;\n"
            f"    iifname {{ {ifs} }} ether type ip ip saddr {victim_ip} counter drop\n"
            f"    iifname {{ {ifs} }} ether type ip ip daddr {victim_ip} counter drop\n"
            f"  }}\n}}\n")


def nft_apply(fabric_ns: str, ruleset: str) -> None:
    kernel.run(["ip", "netns", "exec", fabric_ns, "nft", "-f", "-"], input_text=ruleset)


def blackhole_on(fabric_ns: str, table: str, ports: list[str], victim_ip: str) -> None:
    nft_apply(fabric_ns, blackhole_ruleset(table, ports, victim_ip))


def blackhole_off(fabric_ns: str, table: str) -> int:
    """Delete the table; returns how many frames it dropped (both rules)."""
    dropped = 0
    r = kernel.run(["ip", "netns", "exec", fabric_ns, "nft", "-j", "list", "table", "bridge", table], check=False)
    if r.returncode == 0:
        for item in json.loads(r.stdout).get("nftables", []):
            for expr in item.get("rule", {}).get("expr", []):
                if isinstance(expr, dict) and "counter" in expr:
                    dropped += int(expr["counter"].get("packets", 0))
        kernel.run(["ip", "netns", "exec", fabric_ns, "nft", "delete", "table", "bridge", table])
    return dropped


def mirror_lines(victim_port: str, attacker_port: str) -> list[str]:
    act = f"action mirred egress mirror dev {attacker_port}"
    return [f"qdisc replace dev {victim_port} clsact",
            f"filter add dev {victim_port} ingress protocol ip prio 7 u32 match u32 0 0 {act}",
            f"filter add dev {victim_port} egress protocol ip prio 7 u32 match u32 0 0 {act}"]


def mirror_on(fabric_ns: str, victim_port: str, attacker_port: str) -> None:
    kernel.run_batch("tc", fabric_ns, mirror_lines(victim_port, attacker_port))


def mirror_off(fabric_ns: str, victim_port: str) -> None:
    # Only the replay puts a clsact on a host port; deleting it removes both filters.
    kernel.run(["tc", "-n", fabric_ns, "qdisc", "del", "dev", victim_port, "clsact"], check=False)
