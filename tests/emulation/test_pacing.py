"""The delay stage's pacing (`emulation.pacing`) is the fidelity audit's link model, frame for frame."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.emulation.pacing import PacedPort, Pacing
from uavcas.fidelity import fifo

T0_NS = 10**12  # monotonic nanoseconds, far from 0


def _paced(ready_s, length_b, pacing: Pacing) -> tuple[PacedPort, list]:
    port = PacedPort(pacing)
    starts = [port.admit(T0_NS + round(r * 1e9), int(n), k) for k, (r, n) in enumerate(zip(ready_s, length_b))]
    return port, starts


@pytest.mark.parametrize("seed", range(5))
def test_schedule_is_the_audits_fifo(seed):
    rng = np.random.default_rng(seed)
    n = 3000
    # bursts over a saturated 2 Mbit/s link, with idle gaps: every branch of the bucket is taken
    gaps = np.where(rng.random(n) < 0.05, rng.exponential(0.05, n), rng.exponential(0.002, n))
    ready = np.cumsum(gaps)
    length = rng.choice([60, 66, 590, 1242, 1514], size=n)
    _, starts = _paced(ready, length, Pacing(2_000_000, 1600, 0))
    model = fifo.serve(ready, length, np.array([0.0]), np.array([2.0]), 1600)
    got = (np.array(starts, dtype=np.float64) - T0_NS) / 1e9
    # integer nanoseconds: at most 1 ns of rounding per frame
    assert np.max(np.abs(got - model)) < n * 1e-9
    assert np.mean(got > ready + 1e-3) > 0.2  # the link was saturated, not idle


def test_queue_tail_is_dropped_and_not_charged():
    ready = np.zeros(50)
    port, starts = _paced(ready, np.full(50, 1514), Pacing(1_000_000, 1600, 10))
    # two start at once (the bucket's 1600 B hold the first frame and a little), ten wait, the
    # other 38 find the queue full
    assert starts[0] == starts[1] == T0_NS and all(s is not None for s in starts[:12])
    assert all(s is None for s in starts[12:]) and (port.paced, port.drops) == (12, 38)
    # a drop costs nothing: the next frame after the queue drained starts on time
    later = port.admit(T0_NS + 10**9, 1514, 99)
    assert later == T0_NS + 10**9


def test_a_rate_change_retimes_the_frames_not_started():
    ready = np.zeros(40)
    length = np.full(40, 1000)
    port, starts = _paced(ready, length, Pacing(1_000_000, 1600, 0))
    change_ns = T0_NS + 50_000_000  # 50 ms in: 6 frames started (one every 8 ms)
    port.prune(change_ns, 0)
    port.pacing = Pacing(4_000_000, 1600, 0)
    port.retime()
    got = np.array([s for s in starts[:len(starts) - len(port.frames)]] + [f[1] for f in port.frames], dtype=np.float64)
    model = fifo.serve(ready, length, np.array([-1.0, 0.05]), np.array([1.0, 4.0]), 1600)
    assert np.max(np.abs((got - T0_NS) / 1e9 - model)) < 1e-6
    assert len(port.frames) == int(np.sum(model > 0.05)) == 32  # 8 started (two at once: the bucket's credit)
