"""The switch fabric: one namespace `<prefix>-fab` holding one Linux bridge per node.

Bridge `s<i>` is node i's switch; `h<i>` is its port to the node (peer `eth0` in the node's
namespace); `l<i>-<j>` is its port to switch j (peer `l<j>-<i>`), whose egress shapes the
direction i -> j. Switch-to-switch veths are created *down* with learning and all flooding off
and their qdiscs in place (configuring ports before they come up is what keeps a bridge mesh
from melting into a broadcast storm, EMULATION-NOTES section 8), then toggled per window at
both ends. Forwarding is only the static FDB from `uavcas.network.forwarding`; no STP (its 2 s+ forward delay
cannot follow 5 s windows).

Every step is one batched call per tool: `ip -batch`, `bridge -batch`, `tc -batch`, `nft -f`.
"""

from __future__ import annotations

import json
import subprocess
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from uavcas.network.forwarding import Detour, Forwarding
from uavcas.network.naming import Naming

from . import kernel
from .hosts import HostSpec
from .shaping import Shaper

LinkKey = tuple[int, int]  # (i, j) with i < j: an undirected switch-to-switch link

PORT_FLAGS = "learning off flood off mcast_flood off bcast_flood off"
DETOUR_TABLE = "uavcas_detour"


@dataclass(frozen=True)
class SwitchPorts:
    """The names a runner needs to capture, mirror or filter at one node's switch."""

    node: str
    bridge: str
    host_port: str
    link_ports: dict[str, str]  # neighbour node -> port towards it (links created so far)

    @property
    def all_ports(self) -> list[str]:
        return [self.host_port, *self.link_ports.values()]


def update_order(fdb: dict[tuple[int, str], str]) -> list[tuple[int, str]]:
    """The entries of a (loop-free) static FDB by their hop count to the destination along it,
    nearest first (ties by switch and MAC, so the order is deterministic). An entry whose port
    leads to a switch without an entry for that MAC counts one hop (the frame is dropped there)."""
    depth: dict[tuple[int, str], int] = {}

    def hops(start: tuple[int, str]) -> int:
        chain: list[tuple[int, str]] = []  # entries met on the way, their depth still unknown
        k: tuple[int, str] | None = start
        base = 0  # the depth past the last entry of the chain
        while k is not None:
            if k in depth:
                base = depth[k]
                break
            if k in chain:
                raise ValueError(f"forwarding loop towards {k[1]} at switch {k[0]}")
            chain.append(k)
            nxt = Naming.link_peer(fdb[k])
            k = (nxt, k[1]) if nxt is not None and (nxt, k[1]) in fdb else None
        for c in reversed(chain):
            base = depth[c] = base + 1
        return depth[start]

    return sorted(fdb, key=lambda k: (hops(k), k))


@dataclass(frozen=True)
class PlannedUpdate:
    """A window change's FDB work computed ahead (`Fabric.plan_update`), and what it was computed
    from: valid while the fabric still holds that very FDB and those known detours."""

    fwd: Forwarding
    from_fdb: dict[tuple[int, str], str]
    known: tuple[tuple[str, str], ...]
    want: dict[tuple[int, str], str]
    lines: list[str]


def key(i: int, j: int) -> LinkKey:
    if i == j:
        raise ValueError("a link needs two different switches")
    return (i, j) if i < j else (j, i)


class Fabric:
    def __init__(self, naming: Naming, hosts: Sequence[HostSpec], shaper: Shaper) -> None:
        self.naming = naming
        self.ns = naming.fabric_ns
        self.hosts = sorted(hosts, key=lambda h: h.index)
        self.by_name = {h.name: h for h in self.hosts}
        self.shaper = shaper
        self.created: set[LinkKey] = set()
        self.up: set[LinkKey] = set()
        self.fdb: dict[tuple[int, str], str] = {}  # (switch index, dst MAC) -> port
        self.detours_active: tuple[tuple[str, str], ...] = ()  # (victim, bs) diverting now
        self.detours_known: dict[tuple[str, str], Detour] = {}
        self._planned: PlannedUpdate | None = None

    # setup -------------------------------------------------------------------------------
    def setup(self, precreate: Iterable[LinkKey] = ()) -> dict[str, float]:
        """Bridges, host links and the given switch links (down). Node namespaces must exist."""
        t0 = time.perf_counter()
        ip, br = [], []
        for h in self.hosts:
            s, hp = Naming.bridge(h.index), Naming.host_port(h.index)
            ip += [f"link add {s} type bridge stp_state 0 mcast_snooping 0",
                   f"link add {hp} type veth peer name {Naming.HOST_IF} address {h.mac} netns {h.ns}",
                   f"link set {hp} master {s}"]
            br += [f"link set dev {hp} {PORT_FLAGS}",
                   f"fdb replace {h.mac} dev {hp} master static"]
        links = sorted(set(precreate) - self.created)
        ip += self._link_add_lines(links)
        kernel.run_batch("ip", self.ns, ip)
        t1 = time.perf_counter()
        br += self._link_flag_lines(links)
        kernel.run_batches([kernel.Batch("bridge", self.ns, br), *self.shaper.init_batches(self._ports(links))])
        self.created |= set(links)
        t2 = time.perf_counter()
        up = [f"link set {Naming.bridge(h.index)} up" for h in self.hosts]
        up += [f"link set {Naming.host_port(h.index)} up" for h in self.hosts]
        kernel.run_batch("ip", self.ns, up)
        return {"create_s": t1 - t0, "configure_s": t2 - t1, "up_s": time.perf_counter() - t2}

    @staticmethod
    def _ports(links: Iterable[LinkKey]) -> list[str]:
        return [p for i, j in links for p in (Naming.link_port(i, j), Naming.link_port(j, i))]

    @staticmethod
    def _link_add_lines(links: Iterable[LinkKey]) -> list[str]:
        lines = []
        for i, j in links:
            a, b = Naming.link_port(i, j), Naming.link_port(j, i)
            lines += [f"link add {a} type veth peer name {b}",
                      f"link set {a} master {Naming.bridge(i)}", f"link set {b} master {Naming.bridge(j)}"]
        return lines

    def _link_flag_lines(self, links: Iterable[LinkKey]) -> list[str]:
        return [f"link set dev {p} {PORT_FLAGS}" for p in self._ports(links)]

    def ensure_links(self, links: Iterable[LinkKey]) -> int:
        """Create (down, configured, shaped) any link not created yet: 'created on first use'."""
        new = sorted(set(links) - self.created)
        if new:
            kernel.run_batch("ip", self.ns, self._link_add_lines(new))
            kernel.run_batches([kernel.Batch("bridge", self.ns, self._link_flag_lines(new)),
                                *self.shaper.init_batches(self._ports(new))])
            self.created |= set(new)
        return len(new)

    # per window ----------------------------------------------------------------------------
    def toggle_lines(self, active: set[LinkKey]) -> tuple[list[str], list[str]]:
        """`ip -batch` lines taking links down and up (both ends) so that exactly `active` is up."""
        down = sorted(self.up - active)
        up = sorted(active - self.up)
        return [f"link set {p} down" for p in self._ports(down)], [f"link set {p} up" for p in self._ports(up)]

    def set_links(self, active: set[LinkKey]) -> tuple[int, int]:
        """Bring exactly `active` up (both ends) and everything else down, in one batch."""
        down, up = self.toggle_lines(active)
        kernel.run_batch("ip", self.ns, down + up)
        self.up = set(active)
        return len(up) // 2, len(down) // 2

    def wait_operational(self, ports: Sequence[str], timeout_s: float = 1.0) -> bool:
        """Wait until these ports' operational state is up (their queues attached); False on timeout."""
        want = set(ports)
        deadline = time.monotonic() + timeout_s
        while want:
            t = time.monotonic()
            out = kernel.run(["ip", "-n", self.ns, "-j", "link", "show"]).stdout
            want -= {d["ifname"] for d in json.loads(out or "[]") if d.get("operstate") == "UP"}
            took = time.monotonic() - t
            if not want or time.monotonic() + took + 0.01 > deadline:  # another look would overrun
                break
            time.sleep(0.01)
        return not want

    def desired_fdb(self, fwd: Forwarding) -> dict[tuple[int, str], str]:
        want: dict[tuple[int, str], str] = {}
        for sw_name, table in fwd.next_hop.items():
            i = self.by_name[sw_name].index
            for dst, nh in table.items():
                want[(i, self.by_name[dst].mac)] = Naming.link_port(i, self.by_name[nh].index)
        # Detours seen before keep their alias entries (only frames already diverted use them,
        # and those still in flight when a detour stops must arrive); active ones take precedence.
        stale = [d for k, d in self.detours_known.items() if k not in {(x.victim, x.bs) for x in fwd.detours}]
        for d in [*stale, *fwd.detours]:
            for (sw, alias), (nh, _) in d.alias_hops().items():
                i = self.by_name[sw].index
                want[(i, self.alias_mac(alias))] = Naming.link_port(i, self.by_name[nh].index)
        return want

    # wormhole detours (see uavcas.network.forwarding) ------------------------------------------
    def alias_mac(self, alias: str) -> str:
        """MAC of alias 'a>b' (frames from a to b on a detour): locally administered, 02:77:..."""
        a, b = (self.by_name[x].index for x in alias.split(">"))
        return f"02:77:{a >> 8:02x}:{a & 0xFF:02x}:{b >> 8:02x}:{b & 0xFF:02x}"

    def detour_ruleset(self, active: Iterable[Detour], known: Iterable[Detour]) -> str:
        """The nft bridge table rewriting destination MACs for detours (one atomic transaction).

        For each active detour the sender's switch turns the victim's frames to bs (and bs's
        frames to the victim) into the alias, at its host port, before the FDB lookup. Every
        detour ever installed keeps its restore rules (alias -> real MAC on the receiving
        switch's link ports), so frames still in flight when a detour stops are delivered.

        The table and its base chain are declared, never deleted: only the chain's rules are
        replaced. Deleting a base chain unregisters its netfilter hook, and the kernel then drops
        every packet held in an NFQUEUE of the namespace (`nf_queue_nf_hook_drop`): the delay
        stage's frames of every port, which its pacer had already charged link time for. A medium
        run lost 20-100 frames at each rewrite and its links ran up to 350 ms late after it.
        """
        rules = []
        for d in active:
            for src, dst in ((d.victim, d.bs), (d.bs, d.victim)):
                hs, hd = self.by_name[src], self.by_name[dst]
                rules.append(f'iifname "{Naming.host_port(hs.index)}" ether saddr {hs.mac} '
                             f'ether daddr {hd.mac} ether daddr set {self.alias_mac(f"{src}>{dst}")}')
        for d in known:
            for src, dst in ((d.victim, d.bs), (d.bs, d.victim)):
                hd = self.by_name[dst]
                ports = Naming.link_port(hd.index, 0).rsplit("-", 1)[0] + "-*"
                rules.append(f'iifname "{ports}" ether daddr {self.alias_mac(f"{src}>{dst}")} '
                             f'ether daddr set {hd.mac}')
        return (f"table bridge {DETOUR_TABLE} {{\n  chain pre {{ type filter hook prerouting priority -300; "
                f"policy accept; }}\n}}\nflush chain bridge {DETOUR_TABLE} pre\n"
                + "".join(f"add rule bridge {DETOUR_TABLE} pre {r}\n" for r in rules))

    def apply_detours(self, active: Sequence[Detour]) -> bool:
        """Make exactly `active` divert (restore rules kept for all seen); False when unchanged."""
        keys = tuple(sorted((d.victim, d.bs) for d in active))
        known = {**self.detours_known, **{(d.victim, d.bs): d for d in active}}
        if keys == self.detours_active and known.keys() == self.detours_known.keys():
            return False
        kernel.run(["ip", "netns", "exec", self.ns, "nft", "-f", "-"],
                   input_text=self.detour_ruleset(active, [known[k] for k in sorted(known)]))
        self.detours_active, self.detours_known = keys, known
        return True

    def fdb_lines(self, want: dict[tuple[int, str], str]) -> list[str]:
        """Replace changed static FDB entries; delete those whose destination became unreachable
        (with flooding off, a frame without an entry is dropped: no path, no traffic).

        Make-before-break: `bridge -batch` applies its lines one at a time while frames flow, so
        every prefix of the batch is a forwarding state. Deletions come first (a frame without an
        entry is dropped, never looped), then the replacements nearest their destination first
        (`update_order`): a switch takes its new next hop only once that hop and every hop after
        it already forward on the new tables, so no intermediate state holds a loop.
        """
        lines = [f"fdb del {mac} dev {port} master" for (i, mac), port in sorted(self.fdb.items())
                 if (i, mac) not in want]
        changed = [k for k in update_order(want) if self.fdb.get(k) != want[k]]
        lines += [f"fdb replace {mac} dev {want[(i, mac)]} master static" for i, mac in changed]
        return lines

    def plan_update(self, fwd: Forwarding) -> tuple[dict[tuple[int, str], str], list[str]]:
        """The FDB `fwd` needs and the batch taking the current FDB there, memoised for one
        (forwarding, current FDB, known detours): a runner plans the next window's change in idle
        time (ordering 10,000 entries takes ~30 ms at 100 UAVs), and the change only replays it.
        The current FDB is matched by identity: it is replaced, never edited in place."""
        known = tuple(self.detours_known)
        p = self._planned
        if p is None or p.fwd is not fwd or p.from_fdb is not self.fdb or p.known != known:
            want = self.desired_fdb(fwd)
            p = self._planned = PlannedUpdate(fwd, self.fdb, known, want, self.fdb_lines(want))
        return p.want, p.lines

    def apply_forwarding(self, fwd: Forwarding) -> int:
        want, lines = self.plan_update(fwd)
        kernel.run_batch("bridge", self.ns, lines)
        self.fdb = want
        return len(lines)

    # hooks for traffic, attacks and capture --------------------------------------------------
    def switch(self, node: str) -> SwitchPorts:
        i = self.by_name[node].index
        names = {h.index: h.name for h in self.hosts}
        ports = {names[j if i == a else a]: Naming.link_port(i, j if i == a else a)
                 for a, j in sorted(self.created) if i in (a, j)}
        return SwitchPorts(node, Naming.bridge(i), Naming.host_port(i), ports)

    def nft(self, ruleset: str) -> None:
        """Apply an nft ruleset (one transaction) in the fabric namespace, e.g. a bridge blackhole table."""
        kernel.run(["ip", "netns", "exec", self.ns, "nft", "-f", "-"], input_text=ruleset)

    def nft_delete_table(self, name: str, family: str = "bridge") -> None:
        """Remove a table added with `nft` (absent is fine: removal is idempotent)."""
        kernel.run(["ip", "netns", "exec", self.ns, "nft", "-f", "-"],
                   input_text=f"table {family} {name}\ndelete table {family} {name}\n")

    def mirror(self, from_port: str, to_port: str, direction: str = "ingress") -> None:
        """Copy every IPv4 frame entering (or leaving) `from_port` to `to_port` (act_mirred)."""
        kernel.run_batch("tc", self.ns, [
            f"qdisc replace dev {from_port} clsact",
            f"filter add dev {from_port} {direction} protocol ip prio 1 u32 match u32 0 0 "
            f"action mirred egress mirror dev {to_port}"])

    def unmirror(self, port: str) -> None:
        kernel.run(["tc", "-n", self.ns, "qdisc", "del", "dev", port, "clsact"], check=False)

    def argv(self, argv: Sequence[str], timeout_s: float | None = None) -> list[str]:
        inner = ["ip", "netns", "exec", self.ns, *argv]
        return kernel.timed(inner, timeout_s) if timeout_s is not None else inner

    def popen(self, argv: Sequence[str], timeout_s: float | None = None, **kw) -> subprocess.Popen:
        return subprocess.Popen(self.argv(argv, timeout_s), **kw)
