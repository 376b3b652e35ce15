"""Topology figures: one PNG per window, links coloured by MCS, attack roles marked."""

from __future__ import annotations

from pathlib import Path

from matplotlib.collections import LineCollection

from uavcas.twin.model import Plan, Window

from .figure import plt, save_png


def _roles(plan: Plan, w: Window) -> dict[str, str]:
    roles: dict[str, str] = {}
    t0, t1 = w.t_s, w.t_s + w.duration_s
    for a in plan.attacks:
        if a.start_s < t1 and a.stop_s > t0:
            for v in a.victims:
                roles[v] = "victim"
            for x in a.attackers:
                roles.setdefault(x, f"attacker ({a.family})")
    return roles


def draw_window(plan: Plan, w: Window, ax) -> None:
    pos = w.positions
    cmap = plt.get_cmap("viridis", 7)
    segs, colours, widths = [], [], []
    for lk in w.links:
        (xa, ya, _), (xb, yb, _) = pos[lk.a], pos[lk.b]
        segs.append([(xa, ya), (xb, yb)])
        colours.append("0.4" if lk.mcs is None else cmap(lk.mcs))
        widths.append(3.0 if lk.kind == "backhaul" else 1.2 + 2.0 * (1 - min(1.0, lk.loss * 10)))
    ax.add_collection(LineCollection(segs, colors=colours, linewidths=widths, zorder=1))
    roles = _roles(plan, w)
    for nd in plan.nodes:
        x, y, z = pos[nd.name]
        role = roles.get(nd.name, "")
        face = "tab:red" if role.startswith("attacker") else "tab:orange" if role == "victim" else (
            "black" if nd.kind == "bs" else "tab:blue")
        ax.scatter([x], [y], marker="^" if nd.kind == "bs" else "o", s=70 if nd.kind == "bs" else 30,
                   c=face, zorder=2, edgecolors="white", linewidths=0.5)
        ax.annotate(nd.name, (x, y), fontsize=6, xytext=(3, 3), textcoords="offset points")
    x_max, y_max = plan.area_m[0], plan.area_m[1]
    ax.set_xlim(0, x_max)
    ax.set_ylim(0, y_max)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    active = sorted({r.split(" ")[-1].strip("()") for r in roles.values() if r.startswith("attacker")})
    ax.set_title(
        f"window {w.index} (t={w.t_s:g} s): {len(w.links)} links"
        + (f", attacks: {', '.join(active)}" if active else ""),
        fontsize=9,
    )


def draw_plan_windows(plan: Plan, out_dir: str | Path) -> list[Path]:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    sm = plt.cm.ScalarMappable(cmap=plt.get_cmap("viridis", 7), norm=plt.Normalize(-0.5, 6.5))
    for w in plan.windows:
        fig, ax = plt.subplots(figsize=(6.4, 5.6), dpi=110)
        draw_window(plan, w, ax)
        fig.colorbar(sm, ax=ax, ticks=range(7), label="MCS (grey: wired backhaul)")
        fig.suptitle(plan.config, fontsize=8)
        path = out_dir / f"topology_w{w.index:02d}.png"
        # full canvas at the figure's dpi: every window's PNG has the same size and axes
        paths.append(save_png(fig, path, dpi="figure", tight=False))
    return paths
