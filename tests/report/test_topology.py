"""Topology at an attack's start: the window holding the start, roles and disconnected UAVs in the legend."""

from __future__ import annotations

from uavcas.figure import plt
from uavcas.report.topology import attack_start_figure, disconnected_uavs, draw_window, window_at
from uavcas.twin.model import Route
from uavcas.twin.plan import plan as make_plan


def _legend_texts(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_attack_start_window_roles_and_mcs_legend():
    p = make_plan("blackhole+dos=1000-5-2-image-logdist-adaptive-spiral-30-95", seed=3, windows=4, window_s=5.0)
    fig = attack_start_figure(p)
    assert len(fig.axes) == len(p.attacks) == 2
    for a, ax in zip(p.attacks, fig.axes):
        w = window_at(p, a.start_s)
        assert w.t_s <= a.start_s < w.t_s + w.duration_s and f"window {w.index}" in ax.get_title()
        texts = _legend_texts(ax)
        assert {"attacker", "victim", "UAV", "base station", "wired backhaul"} <= set(texts)
        assert {f"MCS {lk.mcs}" for lk in w.links if lk.mcs is not None} <= set(texts)
    plt.close(fig)
    assert window_at(p, -1.0).index == 0 and window_at(p, 1e6).index == len(p.windows) - 1
    assert attack_start_figure(make_plan("benign-5-2-image-logdist-adaptive-spiral-30-95", seed=3, windows=2)) is None


def test_a_disconnected_uav_is_marked_and_named_in_the_legend():
    p = make_plan("benign-5-2-image-logdist-adaptive-spiral-30-95", seed=3, windows=2)
    w = p.windows[0]
    cut = w.model_copy(update={"routes": [*w.routes, Route(src="uav3", dst="bs1", hops=[], disconnected=True)]})
    assert disconnected_uavs(p, cut) == {"uav3"} and disconnected_uavs(p, w) == set()
    fig, ax = plt.subplots()
    draw_window(p, cut, ax)
    assert any(t.startswith("disconnected UAV") for t in _legend_texts(ax))
    plt.close(fig)
