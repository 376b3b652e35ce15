"""The shaping in force on each port by time (fidelity.inforce), from the run's applies."""

from __future__ import annotations

import numpy as np

from helpers.fidsynth import link, plan
from uavcas.fidelity.inforce import port_shaping
from uavcas.flows.follow import Timeline
from uavcas.network.queues import netem_limit_pkts, queue_limit_pkts
from uavcas.rundir import ForwardingEpoch
from uavcas.twin.model import Window


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


def test_an_attack_reshape_splits_the_window_into_segments_with_the_parameters_in_force():
    from uavcas.fidelity.inforce import ShapeSpan
    from uavcas.twin.model import LinkOverride

    p = _plan()
    jam = LinkOverride(attack_id="jamming-0", src="uav0", dst="uav1", start_s=6.0, stop_s=8.0,
                       interference_dbm=-60.0, sinr_db=5.0, mcs=0, rate_mbps=0.5, delay_ms=3.0, loss=0.4)
    w1 = p.windows[1].model_copy(update={"link_overrides": [jam]})
    p = p.model_copy(update={"windows": [p.windows[0], w1, p.windows[2]]})
    # the jammer's start reshaped at [106.0, 106.02) and logged 106.02; its stop logged 108.0,
    # the unjammed shaping back at 108.03
    span = ShapeSpan("jamming-0", start_unix=106.02, stop_unix=108.0, from_unix=106.0, until_unix=108.03)
    ps = port_shaping(p, _timeline(p), [span])
    a, back = ps[(0, 1)], ps[(1, 0)]
    assert a.t_s.tolist() == [100.0, 105.0, 106.0, 108.0] and a.until_s.tolist() == [100.05, 105.1, 106.02, 108.03]
    assert a.window.tolist() == [0, 1, 1, 1] and a.segment.tolist() == [0, 0, 1, 2]
    # jammed only in segment 1 and only in the overridden direction
    assert a.rate_mbps.tolist() == [8.0, 4.0, 0.5, 4.0] and a.loss.tolist() == [0.0, 0.1, 0.4, 0.1]
    assert back.rate_mbps.tolist() == [8.0, 4.0, 4.0, 4.0] and back.segment.tolist() == [0, 0, 1, 2]
    assert a.at(np.array([106.01, 107.9, 108.1])).tolist() == [2, 2, 3]
    # a jammer that starts late in window 1 and lasts into window 2: window 2 is applied jammed
    # (its segment 0) and the stop inside it starts segment 1
    w2 = p.windows[2].model_copy(update={"links": [link("uav0", "uav1", 4.0, 3.0, 0.1)], "link_overrides": [
        jam.model_copy(update={"start_s": 10.0, "stop_s": 12.0})]})
    p2 = p.model_copy(update={"windows": [p.windows[0], p.windows[1], w2]})
    span2 = ShapeSpan("jamming-0", start_unix=109.0, stop_unix=112.0, from_unix=109.0, until_unix=112.01)
    a2 = port_shaping(p2, _timeline(p2), [span2])[(0, 1)]
    assert a2.t_s.tolist() == [100.0, 105.0, 109.0, 110.0, 112.0] and a2.segment.tolist() == [0, 0, 1, 0, 1]
    assert a2.window.tolist() == [0, 1, 1, 2, 2] and a2.rate_mbps.tolist() == [8.0, 4.0, 0.5, 0.5, 4.0]
