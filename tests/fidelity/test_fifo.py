"""The FIFO model of a link, against values worked out by hand.

Rate 8 Mbit/s = 1 byte per microsecond, so a frame of L bytes costs L microseconds of tokens;
the bucket holds 1600 bytes (1600 us) and a frame may start whenever the bucket is not in debt.
"""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.fidelity import fifo

US = 1e-6


def _serve(ready_us, length, rate=8.0, burst=1600, change_us=(), rates=()):
    """Start times (us) at `rate`, then `rates[k]` from `change_us[k]` on."""
    t = np.array([0.0, *change_us]) * US
    return fifo.serve(np.array(ready_us, float) * US, np.array(length, float), t, np.array([rate, *rates]),
                      burst) / US


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
    got = _serve([0] * 4, [1000] * 4, change_us=[300], rates=[16.0])
    # third frame starts at 400 us (debt of the first two at 8 Mbit/s), after the change: it and
    # the fourth cost 500 us each
    assert got == pytest.approx([0, 0, 400, 900])


def test_frames_queued_across_a_change_are_charged_at_the_new_rate():
    # all ready at 0 under 8 Mbit/s; the port goes to 16 Mbit/s at 1000 us: the fourth frame
    # starts at 1400 us, after the change, and costs 500 us, not 1000 (HTB charges at dequeue)
    got = _serve([0] * 5, [1000] * 5, change_us=[1000], rates=[16.0])
    assert got == pytest.approx([0, 0, 400, 1400, 1900])


# A change known only to lie in [1000, 3000) us, 8 -> 16 Mbit/s, ten 1000-byte frames ready at 0.
# With the first h frames that start from 1000 us on still at 8 Mbit/s (frame 3 starts at 1400):
AT_CHANGE = {
    0: [0, 0, 400, 1400, 1900, 2400, 2900, 3400, 3900, 4400],  # the change at 1000 us
    1: [0, 0, 400, 1400, 2400, 2900, 3400, 3900, 4400, 4900],  # between frames 3 and 4
    2: [0, 0, 400, 1400, 2400, 3400, 3900, 4400, 4900, 5400],  # between frames 4 and 5
}


def _serve_uncertain(seen_us):
    return fifo.serve(np.zeros(10), np.full(10, 1000.0), np.array([0.0, 1000 * US]), np.array([8.0, 16.0]), 1600,
                      np.array([0.0, 3000 * US]), None if seen_us is None else np.array(seen_us, float) * US) / US


def test_an_uncertain_change_is_placed_where_the_measured_starts_say():
    jitter = np.array([30, -20, 10, -30, 20, -10, 30, -20, 10, 0])  # capture noise, well under a frame
    for h, starts in AT_CHANGE.items():
        assert _serve_uncertain(np.array(starts) + jitter) == pytest.approx(starts), h
    # without measured starts the change is taken at the start of its interval
    assert _serve_uncertain(None) == pytest.approx(AT_CHANGE[0])


def test_an_uncertain_change_happened_by_the_end_of_its_interval():
    # measured as if the rate never changed: frame 5 at the old rate would start at 3400 us, after
    # the apply ended, so the latest candidate is the change before frame 5
    assert _serve_uncertain([0, 0, 400, 1400, 2400, 3400, 4400, 5400, 6400, 7400]) == pytest.approx(AT_CHANGE[2])


def test_backlog_and_busy_intervals():
    ready = np.array([0, 0, 0, 0, 5000]) * US
    start = _serve([0, 0, 0, 0, 5000], [1000] * 5) * US
    assert fifo.backlog(ready, start, np.array([0, 500, 1500, 5000]) * US).tolist() == [2, 1, 0, 0]
    busy = fifo.busy_intervals(ready, start) / US
    assert busy == pytest.approx(np.array([[0, 1400]]))
    assert fifo.busy_intervals(ready[:1], start[:1]).shape == (0, 2)
