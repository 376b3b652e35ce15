"""The fabric's window change without a kernel: the FDB batch's order (issue 28, item 2's last
bullet). `bridge -batch` applies its lines one at a time while frames flow, so every prefix of
the batch is a forwarding state, and none may hold a loop."""

from __future__ import annotations

import itertools
import random
import re

import pytest

from uavcas.emulation.fabric import Fabric, update_order
from uavcas.emulation.hosts import HostSpec
from uavcas.network.forwarding import Detour, compute
from uavcas.network.naming import Naming

FDB_LINE = re.compile(r"fdb (replace|del) (\S+) dev (\S+) master(?: static)?")


def _fabric(nodes: list[str]) -> Fabric:
    hosts = [HostSpec(n, i, f"10.0.0.{i + 1}", f"02:00:00:00:00:{i:02x}", f"uc0-{n}") for i, n in enumerate(nodes)]
    return Fabric(Naming("uc0"), hosts, shaper=None)


def _switch_of(line_dev: str) -> int:
    return int(re.fullmatch(r"l(\d+)-\d+", line_dev).group(1))


def _loops(state: dict[tuple[int, str], str]) -> list[tuple[int, str]]:
    """(switch, MAC) pairs from which a frame comes back to a switch it crossed."""
    bad = []
    for (i, mac) in state:
        seen, k = set(), (i, mac)
        while k in state:
            if k[0] in seen:
                bad.append((i, mac))
                break
            seen.add(k[0])
            nxt = Naming.link_peer(state[k])
            k = (nxt, mac) if nxt is not None else None
    return bad


def _replay(fab: Fabric, lines: list[str]) -> list[int]:
    """Apply the batch line by line to the fabric's FDB; the line numbers after which a loop exists."""
    state = dict(fab.fdb)
    looped = []
    for n, line in enumerate(lines):
        op, mac, dev = FDB_LINE.fullmatch(line).groups()
        if op == "del":
            del state[(_switch_of(dev), mac)]
        else:
            state[(_switch_of(dev), mac)] = dev
        if _loops(state):
            looped.append(n)
    return looped


def _window(rng: random.Random, nodes: list[str], p: float) -> list[tuple[str, str]]:
    return [(a, b) for a, b in itertools.combinations(nodes, 2) if rng.random() < p]


def _changes(seed: int) -> tuple[Fabric, dict, list[str]]:
    rng = random.Random(seed)
    nodes = [f"n{i}" for i in range(12)]
    fab = _fabric(nodes)
    fab.fdb = fab.desired_fdb(compute(nodes, _window(rng, nodes, 0.25)))
    want = fab.desired_fdb(compute(nodes, _window(rng, nodes, 0.25)))
    return fab, want, fab.fdb_lines(want)


@pytest.mark.parametrize("seed", range(40))
def test_every_prefix_of_a_window_change_is_loop_free(seed):
    fab, want, lines = _changes(seed)
    assert _replay(fab, lines) == []
    # and the whole batch lands on the new tables
    state = dict(fab.fdb)
    for line in lines:
        op, mac, dev = FDB_LINE.fullmatch(line).groups()
        state.pop((_switch_of(dev), mac)) if op == "del" else state.__setitem__((_switch_of(dev), mac), dev)
    assert state == want


def test_switch_and_mac_order_would_loop():
    """The order this replaces (sorted by switch, then MAC) leaves loops in some intermediate states
    of the same random window changes: the test above is not vacuous."""
    looped = 0
    for seed in range(40):
        fab, want, _ = _changes(seed)
        plain = [f"fdb del {mac} dev {port} master" for (i, mac), port in sorted(fab.fdb.items())
                 if (i, mac) not in want]
        plain += [f"fdb replace {mac} dev {port} master static" for (i, mac), port in sorted(want.items())
                  if fab.fdb.get((i, mac)) != port]
        looped += bool(_replay(fab, plain))
    assert looped >= 20, looped  # 39 of the 40


def test_update_order_puts_each_hop_after_the_hops_beyond_it():
    # a chain 0 -> 1 -> 2 -> 3 towards node 3's MAC, listed backwards; node 3's switch has no entry
    mac = "02:00:00:00:00:03"
    fdb = {(0, mac): "l0-1", (1, mac): "l1-2", (2, mac): "l2-3", (5, mac): "l5-4"}
    assert update_order(fdb) == [(2, mac), (5, mac), (1, mac), (0, mac)]
    with pytest.raises(ValueError, match="forwarding loop"):
        update_order({(0, mac): "l0-1", (1, mac): "l1-0"})


def test_detour_aliases_are_ordered_along_their_path():
    nodes = ["uav0", "uav1", "uav2", "bs0"]
    links = [("uav0", "uav1"), ("uav1", "uav2"), ("uav2", "bs0"), ("uav0", "bs0")]
    fab = _fabric(nodes)
    fab.fdb = fab.desired_fdb(compute(nodes, links))
    fwd = compute(nodes, links, wormholes=[Detour("uav0", "uav2", "bs0")])
    lines = fab.fdb_lines(fab.desired_fdb(fwd))
    alias = fab.alias_mac("uav0>bs0")
    along = [_switch_of(FDB_LINE.fullmatch(x).group(3)) for x in lines if alias in x]
    assert along == [2, 1, 0]  # uav2 -> bs0 first, the victim's own switch last
    assert _replay(fab, lines) == []


def test_a_planned_update_is_replayed_only_onto_the_fdb_it_was_planned_from():
    nodes = [f"n{i}" for i in range(6)]
    fab = _fabric(nodes)
    fwd = compute(nodes, [("n0", "n1"), ("n1", "n2"), ("n2", "n3"), ("n3", "n4"), ("n4", "n5")])
    want, lines = fab.plan_update(fwd)
    assert fab.plan_update(fwd)[1] is lines  # planned ahead, replayed at the change
    fab.fdb = dict(want)  # the FDB moved on (e.g. a wormhole re-routed mid-window): plan again
    assert fab.plan_update(fwd) == (want, [])
    other = compute(nodes, [("n0", "n5"), ("n1", "n2"), ("n2", "n3"), ("n3", "n4"), ("n4", "n5")])
    assert fab.plan_update(other)[1] and fab.plan_update(other)[1] is fab.plan_update(other)[1]
