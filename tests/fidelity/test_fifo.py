"""The FIFO model of a link, against values worked out by hand.

Rate 8 Mbit/s = 1 byte per microsecond, so a frame of L bytes costs L microseconds of tokens;
the bucket holds 1600 bytes (1600 us) and a frame may start whenever the bucket is not in debt.
"""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.fidelity import fifo

US = 1e-6


def _serve(ready_us, length, rate=8.0, burst=1600):
    n = len(ready_us)
    return fifo.serve(np.array(ready_us, float) * US, np.array(length, float), np.full(n, rate), burst) / US


def test_idle_link_starts_every_frame_when_ready():
    assert _serve([0, 5000, 9000], [1500, 1500, 1500]) == pytest.approx([0, 5000, 9000])


def test_burst_then_the_planned_rate():
    # 1000-byte frames all ready at 0: the full bucket lets two go at once (debt after the
    # second: 1000 - (1600 - 1000) = 400 us), then one every 1000 us.
    assert _serve([0] * 5, [1000] * 5) == pytest.approx([0, 0, 400, 1400, 2400])


def test_bucket_refills_while_idle_up_to_its_depth():
    # after 10 ms idle the bucket is full again (not 10 ms worth of credit): same pattern
    got = _serve([0, 0, 0, 20000, 20000, 20000], [1000] * 6)
    assert got == pytest.approx([0, 0, 400, 20000, 20000, 20400])


def test_fifo_never_reorders_and_small_frames_follow_the_queue():
    got = _serve([0, 0, 0, 10], [1500, 1500, 1500, 64])
    # 1500 first (debt 1500-1600 = -100), second at 0 (debt 1400), third waits to 1400 (debt 2900)
    # and the 64-byte frame behind it cannot pass: it starts with the third at the earliest
    assert got == pytest.approx([0, 0, 1400, 2900])
    assert np.all(np.diff(got) >= 0)


def test_rate_change_applies_to_frames_ready_after_it():
    got = fifo.serve(np.zeros(4), np.full(4, 1000.0), np.array([8.0, 8.0, 16.0, 16.0]), 1600) / US
    # third frame: debt 400 us from the first two at 8 Mbit/s; from there 500 us per frame
    assert got == pytest.approx([0, 0, 400, 900])


def test_backlog_and_busy_intervals():
    ready = np.array([0, 0, 0, 0, 5000]) * US
    start = _serve([0, 0, 0, 0, 5000], [1000] * 5) * US
    assert fifo.backlog(ready, start, np.array([0, 500, 1500, 5000]) * US).tolist() == [2, 1, 0, 0]
    busy = fifo.busy_intervals(ready, start) / US
    assert busy == pytest.approx(np.array([[0, 1400]]))
    assert fifo.busy_intervals(ready[:1], start[:1]).shape == (0, 2)
