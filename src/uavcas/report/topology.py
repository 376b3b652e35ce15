"""Topology figures: links coloured by MCS, attack roles and disconnected UAVs marked, both with a
legend. `draw_plan_windows` writes one PNG per window (`uavcas plan --figure`); `attack_start_figure`
draws a run at each of its attacks' starts (the dataset report), from the window holding the start."""

from __future__ import annotations

from pathlib import Path

from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D

from uavcas.figure import plt, save_png
from uavcas.twin.model import Attack, Plan, Window

N_MCS = 7  # 802.11a/g MCS 0..6 (uavcas.channel.mcs)
BACKHAUL_COLOUR = "0.45"
# marker per role: (label, face colour, marker, size)
ROLE_STYLE: dict[str, tuple[str, str, str, float]] = {
    "attacker": ("attacker", "tab:red", "o", 46),
    "victim": ("victim", "tab:orange", "o", 46),
    "disconnected": ("disconnected UAV (no usable path to its BS)", "white", "X", 52),
    "uav": ("UAV", "tab:blue", "o", 30),
    "bs": ("base station", "black", "^", 80),
}


def _mcs_cmap():
    return plt.get_cmap("viridis", N_MCS)


def window_at(plan: Plan, t_s: float) -> Window:
    """The plan window holding time `t_s` (the last one from its start on, the first before t = 0)."""
    for w in plan.windows:
        if w.t_s <= t_s < w.t_s + w.duration_s:
            return w
    return plan.windows[-1] if t_s >= plan.windows[-1].t_s else plan.windows[0]


def _roles(plan: Plan, w: Window, attacks: list[Attack] | None) -> dict[str, str]:
    """node -> attacker / victim for `attacks` (default: those active during the window)."""
    if attacks is None:
        attacks = [a for a in plan.attacks if a.start_s < w.t_s + w.duration_s and a.stop_s > w.t_s]
    roles: dict[str, str] = {}
    for a in attacks:
        for x in a.victims:
            roles[x] = "victim"
        for x in a.attackers:
            roles.setdefault(x, "attacker")
    return roles


def disconnected_uavs(plan: Plan, w: Window) -> set[str]:
    kinds = {n.name: n.kind for n in plan.nodes}
    return {end for r in w.routes if r.disconnected for end in (r.src, r.dst) if kinds.get(end) == "uav"}


def draw_window(plan: Plan, w: Window, ax, attacks: list[Attack] | None = None, legend: bool = True) -> None:
    """One window on `ax`: links by MCS (width by loss), nodes by role, both legends."""
    pos = w.positions
    cmap = _mcs_cmap()
    segs, colours, widths = [], [], []
    for lk in w.links:
        (xa, ya, _), (xb, yb, _) = pos[lk.a], pos[lk.b]
        segs.append([(xa, ya), (xb, yb)])
        colours.append(BACKHAUL_COLOUR if lk.mcs is None else cmap(lk.mcs))
        widths.append(3.0 if lk.kind == "backhaul" else 1.2 + 2.0 * (1 - min(1.0, lk.loss * 10)))
    ax.add_collection(LineCollection(segs, colors=colours, linewidths=widths, zorder=1))
    roles = _roles(plan, w, attacks)
    cut = disconnected_uavs(plan, w)
    for nd in plan.nodes:
        x, y, _ = pos[nd.name]
        role = "bs" if nd.kind == "bs" and nd.name not in roles else roles.get(nd.name) or (
            "disconnected" if nd.name in cut else "uav")
        _, face, marker, size = ROLE_STYLE[role]
        ax.scatter([x], [y], marker=marker, s=size, c=face, zorder=3,
                   edgecolors="black" if role == "disconnected" else "white", linewidths=0.8)
        ax.annotate(nd.name, (x, y), fontsize=6, xytext=(3, 3), textcoords="offset points")
    ax.set_xlim(0, plan.area_m[0])
    ax.set_ylim(0, plan.area_m[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if legend:
        add_legends(ax, {lk.mcs for lk in w.links}, set(roles.values()) | ({"disconnected"} if cut else set()))


def add_legends(ax, mcs_used: set, roles: set[str]) -> None:
    """Beside the axes: the node markers, then the MCS colours used (and the wired backhaul)."""
    cmap = _mcs_cmap()
    links = [Line2D([], [], color=cmap(m), lw=2.5, label=f"MCS {m}")
             for m in sorted(x for x in mcs_used if x is not None)]
    if None in mcs_used:
        links.append(Line2D([], [], color=BACKHAUL_COLOUR, lw=3, label="wired backhaul"))
    nodes = [Line2D([], [], ls="", marker=ROLE_STYLE[r][2], markersize=7, markerfacecolor=ROLE_STYLE[r][1],
                    markeredgecolor="black", label=ROLE_STYLE[r][0])
             for r in ("attacker", "victim", "disconnected", "uav", "bs") if r in roles or r in ("uav", "bs")]
    # one legend (a second one added as an artist is left out of the tight bounding box: cropped)
    ax.legend(handles=nodes + links, title="node; link colour: MCS (thinner: lossier)", fontsize=7, title_fontsize=7,
              loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)


def attack_start_figure(plan: Plan):
    """One panel per attack of the plan, at its start; None for a plan without attacks."""
    if not plan.attacks:
        return None
    n = len(plan.attacks)
    fig, axes = plt.subplots(1, n, figsize=(6.6 * n, 4.8), squeeze=False, layout="constrained")
    for a, ax in zip(plan.attacks, axes[0]):
        w = window_at(plan, a.start_s)
        draw_window(plan, w, ax, attacks=[a])
        ax.set_title(f"{a.family} starts at t = {a.start_s:.2f} s (window {w.index}, {len(w.links)} links)", fontsize=9)
    return fig


def draw_plan_windows(plan: Plan, out_dir: str | Path) -> list[Path]:
    """One PNG per window of the plan, each the same size (full canvas at the figure's dpi)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for w in plan.windows:
        fig, ax = plt.subplots(figsize=(8.4, 5.6), dpi=110, layout="constrained")
        draw_window(plan, w, ax)
        active = sorted({a.family for a in plan.attacks if a.start_s < w.t_s + w.duration_s and a.stop_s > w.t_s})
        ax.set_title(f"window {w.index} (t = {w.t_s:g} s): {len(w.links)} links"
                     + (f", attacks: {', '.join(active)}" if active else ""), fontsize=9)
        fig.suptitle(plan.config, fontsize=8)
        paths.append(save_png(fig, out_dir / f"topology_w{w.index:02d}.png", dpi="figure", tight=False))
    return paths
