"""A port's queue limits: the emulator's sizing and what the offline models assume are one function."""

from __future__ import annotations

from uavcas.network.queues import MTU_FRAME_B, full_queue_s, netem_limit_pkts, queue_limit_pkts


def test_queue_limit_is_about_50_ms_at_the_rate_within_bounds():
    assert queue_limit_pkts(0.1) == 16 and queue_limit_pkts(10) == 42
    assert queue_limit_pkts(1000.0) == 2000  # capped: 50 ms at 1 Gbit/s would be 4,128 frames


def test_a_full_queue_drains_in_its_frames_serialisation_time():
    assert full_queue_s(10.0) == 42 * MTU_FRAME_B * 8 / 10e6
    assert full_queue_s(0.1) == 16 * MTU_FRAME_B * 8 / 0.1e6  # the floor of 16 frames: longer than 50 ms


def test_netem_limit_adds_the_frames_on_the_wire_during_the_delay():
    assert netem_limit_pkts(10.0, 0.0) == queue_limit_pkts(10.0)
    assert netem_limit_pkts(10.0, 5.0) == 42 + 5  # 10 Mbit/s x 5 ms = 50 kbit: 4.1 frames, rounded up
