"""The shaping in force on each port by time (fidelity.inforce), from the run's applies."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fidsynth import link, plan  # noqa: E402

from uavcas.emulation.shaping import netem_limit_pkts, queue_limit_pkts  # noqa: E402
from uavcas.fidelity.inforce import port_shaping  # noqa: E402
from uavcas.flows.follow import Timeline  # noqa: E402
from uavcas.rundir import ForwardingEpoch  # noqa: E402
from uavcas.twin.model import Window  # noqa: E402


def _plan():
    p = plan()
    w = [Window(index=0, t_s=0.0, duration_s=5.0, positions={}, links=[link("uav0", "uav1", 8.0, 2.0)], routes=[]),
         Window(index=1, t_s=5.0, duration_s=5.0, positions={},
                links=[link("uav0", "uav1", 4.0, 3.0, 0.1), link("uav1", "bs0", 2.0, 1.0)], routes=[]),
         Window(index=2, t_s=10.0, duration_s=5.0, positions={}, links=[link("uav1", "bs0", 6.0, 1.5)], routes=[])]
    return p.model_copy(update={"windows": w})


def _timeline(p):
    # window 1 applied twice (an attack re-routes at 107 s: no shaping change), then window 2,
    # which drops uav0-uav1
    applies = [(100.0, 100.05, 0), (105.0, 105.1, 1), (107.0, 107.01, 1), (110.0, 110.2, 2)]
    epochs = [ForwardingEpoch(t_begin_unix=b, t_unix=e, window=w, next_hop={}) for b, e, w in applies]
    return Timeline.from_epochs(p, epochs)


def test_each_port_changes_setting_when_a_window_with_new_shaping_is_applied():
    ps = port_shaping(_plan(), _timeline(_plan()))
    assert set(ps) == {(0, 1), (1, 0), (1, 2), (2, 1)}
    a = ps[(0, 1)]
    # the re-apply at 107 s is not a new setting; the link leaving at 110 s keeps its last one
    assert a.t_s.tolist() == [100.0, 105.0] and a.until_s.tolist() == [100.05, 105.1]
    assert a.window.tolist() == [0, 1] and a.rate_mbps.tolist() == [8.0, 4.0]
    assert a.delay_ms.tolist() == [2.0, 3.0] and a.loss.tolist() == [0.0, 0.1]
    assert ps[(1, 0)].rate_mbps.tolist() == [8.0, 4.0]
    b = ps[(2, 1)]
    assert b.t_s.tolist() == [105.0, 110.0] and b.window.tolist() == [1, 2] and b.rate_mbps.tolist() == [2.0, 6.0]


def test_setting_in_force_by_time():
    a = port_shaping(_plan(), _timeline(_plan()))[(0, 1)]
    t = np.array([99.0, 100.0, 104.99, 105.0, 105.05, 107.5, 112.0])
    # before the first apply: not shaped; from the start of an apply on: its setting (the port is
    # rewritten in the apply's first phase), whatever window a frame is reported in
    assert a.at(t).tolist() == [-1, 0, 0, 1, 1, 1, 1]


def test_queue_limits_of_settings():
    a = port_shaping(_plan(), _timeline(_plan()))[(0, 1)]
    k = np.array([0, 1, 1])
    assert a.queue_limit_pkts(k).tolist() == [queue_limit_pkts(8.0), queue_limit_pkts(4.0), queue_limit_pkts(4.0)]
    assert a.queue_limit_pkts(k, netem=True).tolist() == [netem_limit_pkts(8.0, 2.0), netem_limit_pkts(4.0, 3.0),
                                                          netem_limit_pkts(4.0, 3.0)]


def test_a_link_that_returns_is_a_new_setting():
    p = _plan()
    epochs = [ForwardingEpoch(t_begin_unix=t, t_unix=t, window=w, next_hop={}) for t, w in ((0, 0), (5, 2), (10, 0))]
    a = port_shaping(p, Timeline.from_epochs(p, epochs))[(0, 1)]
    assert a.t_s.tolist() == [0.0, 10.0] and a.window.tolist() == [0, 0]
