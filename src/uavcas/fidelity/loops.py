"""Which packets that came back to a switch looped, and which were re-routed in flight.

A switch forwards a frame by the table in force when the frame reaches it (the plan's
semantics: one static table per window, `network.forwarding`). A frame queued on a link under
the old table can leave the link after a window change, and the new table can send it back
through a switch it had crossed. In a 20-UAV DDoS run, flood SYNs queued 34 ms on
uav8 -> uav18 reached uav18 after the change and went uav18 -> uav6 -> uav8 -> bs1; in a 100-UAV
run, frames queued 0.6 s on a saturated link went uav59 -> uav20 -> uav64, then, by the new
tables, uav64 -> uav59 -> uav20 -> uav31. No table held a loop.

Such a frame's hops follow the old table up to some hop and the new one from there on: the
fabric updates each switch only after every switch beyond it on the new path
(`emulation.fabric.update_order`), so once a frame takes a new hop, every later switch it meets
is already updated. A revisit is therefore *re-routed in flight* (counted, no failure) when a
forwarding change was under way between the two visits (one began before the second and ended
after the first) and the packet's hops read old-then-new against the tables before and after
that change. Anything else is a *loop*, an emulator fault: a revisit within one forwarding
epoch (each table is loop-free), a hop that follows neither table, or a new hop followed by an
old one, which only a state mixing the two tables in a cycle produces (the switch-and-MAC
update order before stop 26 did: frames went uav5 -> uav4 -> uav2 -> uav5 -> uav4).
"""

from __future__ import annotations

import numpy as np

from uavcas.flows.follow import Followed, Timeline


def rerouted_in_flight(fol: Followed, point_node: np.ndarray, timeline: Timeline, pids: np.ndarray) -> np.ndarray:
    """For each of `pids` (packets with a revisit), True when it was re-routed in flight, False
    when it looped (module docstring). `point_node`: per capture point, its node's index (-1: none)."""
    out = np.zeros(pids.shape[0], dtype=bool)
    begin, end, nh = timeline.t_begin_unix, timeline.t_unix, timeline.next_hop
    for k, p in enumerate(pids.tolist()):
        rows, point, t = fol.visits(p)
        nodes, d = point_node[point], int(fol.dst_node[p])
        revisits = np.flatnonzero(fol.revisit[rows])
        first, last = t[0], t[revisits.max()]
        # the change under way over the packet's revisits: old table = epoch e - 1, new = epoch e
        under_way = np.flatnonzero((begin <= last) & (end > first))
        if d < 0 or under_way.shape[0] != 1 or under_way[0] == 0 or (nodes < 0).any():
            continue
        e = int(under_way[0])
        src, dst = nodes[:-1], nodes[1:]
        old = nh[e - 1, src, d] == dst
        new = nh[e, src, d] == dst
        only_new = np.flatnonzero(new & ~old)
        only_old = np.flatnonzero(old & ~new)
        out[k] = bool((old | new).all()) and not (
            only_new.shape[0] and only_old.shape[0] and only_new.min() < only_old.max())
    return out
