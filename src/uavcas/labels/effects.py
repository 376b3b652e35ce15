"""Per-packet ground truth: one effect per captured packet (`vocabulary.EFFECTS`).

Each attack family's rule says which packets its attacks affected (`AttackFamily.effects` in
`uavcas.attacks.<family>`, one boolean per packet-table row). The rules look at transmissions,
not at single observations: the packet follower (`uavcas.flows.follow`) gives every observation
of one transmitted packet the same `pid`, and an effect found on one observation holds for all of
them, so a flow shows the same truth whichever switch it was captured at.

Each family also says which packets exist only because of the packets its rule marked
(`AttackFamily.provoked`: the victim's SYN-ACK to a flood SYN, the RST answering it, an ICMP
error quoting an attack packet, answers to an injected copy), matched packet to packet; they get
the effect `provoked`, with the provoking family.

A row's effect is the first that applies in `vocabulary.EFFECT_PRECEDENCE`: a family's effect
(made, moved, dropped), else `provoked`, else `channel_loss` when the follower found the
transmission lost on a shaped link (it left a switch towards the next one of the forwarding in
force and never arrived there), else `benign`. So a provoked packet that a blackhole drops shows
the blackhole, and one lost on the channel stays provoked. The family whose rule gave a row its
effect is kept too (`PacketTruth.family`: for a provoked row the provoking family), for
per-family counts and labels. Where two families provoke one row, the first in canonical order
(`vocabulary.FAMILIES`) keeps it, as for two families with one effect.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from uavcas.attacks import families
from uavcas.flows.follow import POINT_PREFIX, Followed, node_of_point
from uavcas.flows.packets import PacketTable, address_to_words
from uavcas.twin.model import Plan
from uavcas.vocabulary import EFFECT_PRECEDENCE, EFFECTS, FAMILIES

from .attacklog import AttackLog

BENIGN = EFFECTS.index("benign")
CHANNEL_LOSS = EFFECTS.index("channel_loss")
PROVOKED = EFFECTS.index("provoked")
# rank of each effect code in EFFECT_PRECEDENCE (lower wins)
_RANK = np.array([EFFECT_PRECEDENCE.index(e) for e in EFFECTS], dtype=np.int64)


@dataclass
class TruthContext:
    """What a family's effect rule may look at: the run's packets, their transmissions (follower),
    the attack log and the plan (node names and windows, placed in time by `t0_unix`). The
    families type against its protocol, `uavcas.attacks.TruthContext`."""

    packets: PacketTable
    log: AttackLog
    followed: Followed
    plan: Plan
    t0_unix: float
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def n(self) -> int:
        return len(self.packets)

    @property
    def ts(self) -> np.ndarray:
        return self.packets["ts_s"]

    def _addr_mask(self, hi: np.ndarray, lo: np.ndarray, ips) -> np.ndarray:
        mask = np.zeros(hi.shape[0], dtype=bool)
        for ip in ips:
            h, l = address_to_words(ip)
            mask |= (hi == np.uint64(h)) & (lo == np.uint64(l))
        return mask

    def packets_from(self, ips) -> np.ndarray:
        return self._addr_mask(self.packets["src_hi"], self.packets["src_lo"], ips)

    def packets_to(self, ips) -> np.ndarray:
        return self._addr_mask(self.packets["dst_hi"], self.packets["dst_lo"], ips)

    def touching(self, ips) -> np.ndarray:
        return self.packets_from(ips) | self.packets_to(ips)

    def during(self, start_unix: float, stop_unix: float) -> np.ndarray:
        return (self.ts >= start_unix) & (self.ts < stop_unix)

    def attacker_to_victim(self, windows, rows: np.ndarray) -> np.ndarray:
        """The rows of `rows` sent from an attacker to a victim of an attack window and captured
        inside [start, observed_until) (a packet that left before the stop may still be crossing)."""
        hit = np.zeros(self.n, dtype=bool)
        for w in windows:
            hit |= rows & self.during(w.start_unix, w.observed_until_unix) & self.packets_from(w.attacker_ips) \
                & self.packets_to(w.victim_ips)
        return hit

    def at_switch_of(self, names) -> np.ndarray:
        """Rows captured at the switch of any of these nodes (capture point s-<node>)."""
        idx = [k for k, p in enumerate(self.packets.points) if p[len(POINT_PREFIX):] in set(names)
               and p.startswith(POINT_PREFIX)]
        return np.isin(self.packets["point"], idx)

    @property
    def point_node(self) -> np.ndarray:
        """Per capture point of the follower, the plan index of its node (-1: not a node's switch;
        [-1] when there are no points, so that indexing it by an empty array works)."""
        if "point_node" not in self._cache:
            index = {x.name: x.index for x in self.plan.nodes}
            self._cache["point_node"] = np.array(
                [index.get(node_of_point(p) or "", -1) for p in self.followed.points] or [-1], dtype=np.int64)
        return self._cache["point_node"]

    def node_names(self, ips) -> list[str]:
        by_ip = {nd.ip: nd.name for nd in self.plan.nodes}
        return [by_ip[ip] for ip in ips if ip in by_ip]

    @property
    def is_last(self) -> np.ndarray:
        """Rows that are their transmission's last observation."""
        if "last" not in self._cache:
            f = self.followed
            last = np.zeros(self.n, dtype=bool)
            if f.n_packets:
                last[f.order[f.offsets[1:] - 1]] = True
            self._cache["last"] = last
        return self._cache["last"]

    @property
    def is_first(self) -> np.ndarray:
        """Rows that are their transmission's first observation (its sender's switch: the
        capture nearest its sending)."""
        if "first" not in self._cache:
            f = self.followed
            first = np.zeros(self.n, dtype=bool)
            if f.n_packets:
                first[f.order[f.offsets[:-1]]] = True
            self._cache["first"] = first
        return self._cache["first"]

    @property
    def window(self) -> np.ndarray:
        """Plan window of each row (by capture time; clipped to the plan's windows)."""
        if "window" not in self._cache:
            w = np.floor((self.ts - self.t0_unix) / self.plan.window_s)
            self._cache["window"] = np.clip(w, 0, len(self.plan.windows) - 1).astype(np.int64)
        return self._cache["window"]

    def spread(self, rows: np.ndarray) -> np.ndarray:
        """Every observation of the transmissions that have a row in `rows`."""
        pid = self.followed.pid
        hit = np.zeros(self.followed.n_packets, dtype=bool)
        hit[pid[rows]] = True
        return hit[pid] if self.n else rows

    def lost_on_link(self) -> np.ndarray:
        """Rows of transmissions the follower found lost on a shaped link (a next switch known)."""
        loss = self.followed.losses
        hit = np.zeros(self.followed.n_packets, dtype=bool)
        hit[loss.pid[loss.to_point >= 0]] = True
        return hit[self.followed.pid] if self.n else np.zeros(0, dtype=bool)


@dataclass(frozen=True)
class PacketTruth:
    """Per packet-table row: its effect (index into EFFECTS) and the family that caused it."""

    effect: np.ndarray  # int8
    family: np.ndarray  # int8, index into FAMILIES (provoked: the provoking one); -1 for benign and channel_loss

    @property
    def is_attack(self) -> np.ndarray:
        return self.family >= 0

    def effect_names(self, rows: np.ndarray | None = None) -> np.ndarray:
        names = np.asarray(EFFECTS, dtype=object)
        return names[self.effect if rows is None else self.effect[rows]]


def packet_truth(ctx: TruthContext) -> PacketTruth:
    """Every row's effect and family (see the module docstring)."""
    effect = np.full(ctx.n, BENIGN, dtype=np.int8)
    fam = np.full(ctx.n, -1, dtype=np.int8)
    effect[ctx.lost_on_link()] = CHANNEL_LOSS
    claims = []
    for f in families():
        windows = ctx.log.of_family(f.name)
        if windows:
            claims.append((EFFECT_PRECEDENCE.index(f.effect), FAMILIES.index(f.name), f))
    # lowest precedence first, so a stronger claim overwrites a weaker one
    made: dict[str, np.ndarray] = {}
    for _, k, f in sorted(claims, key=lambda c: (c[0], c[1]), reverse=True):
        mask = _checked(f.name, "effect", f.effects(ctx, ctx.log.of_family(f.name)), ctx.n)
        made[f.name] = mask
        effect[mask] = EFFECTS.index(f.effect)
        fam[mask] = k
    # then what those packets provoked, on rows with no stronger effect (benign, channel_loss, or
    # provoked by a later family: the lowest family index is applied last and keeps the row)
    for _, k, f in sorted(claims, key=lambda c: c[1], reverse=True):
        mask = _checked(f.name, "provoked", f.provoked(ctx, ctx.log.of_family(f.name), made[f.name]), ctx.n)
        take = mask & (_RANK[effect] >= EFFECT_PRECEDENCE.index("provoked"))
        effect[take] = PROVOKED
        fam[take] = k
    return PacketTruth(effect, fam)


def _checked(name: str, rule: str, mask: np.ndarray, n: int) -> np.ndarray:
    mask = np.asarray(mask, dtype=bool)
    if mask.shape != (n,):
        raise ValueError(f"{name}: {rule} rule returned {mask.shape}, expected ({n},)")
    return mask
