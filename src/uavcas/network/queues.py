"""A switch port's queue: the largest frame it carries and how many frames it holds.

The emulator sizes each shaped port's queue with these (`emulation.shaping`: the pfifo, netem's
limit and the delay stage's pacer), and the offline stages model the same queue with them: the
copy matcher bounds a frame's wait by a full queue (`flows.copies`) and the audit's FIFO model
drops the tail at the same limit (`fidelity.inforce`).
"""

from __future__ import annotations

import math

QUEUE_MS = 50.0  # pfifo sized to ~50 ms at the link rate: no bufferbloat, room for TCP
MTU_FRAME_B = 1514  # the largest Ethernet frame the fabric carries (1500 B MTU): queues and HTB quanta in its units


def queue_limit_pkts(rate_mbps: float) -> int:
    return max(16, min(2000, math.ceil(rate_mbps * 1e6 * QUEUE_MS / 1000 / (MTU_FRAME_B * 8))))


def full_queue_s(rate_mbps: float) -> float:
    """How long a full queue (`queue_limit_pkts` MTU frames) takes to drain at `rate_mbps`: the
    longest a frame can wait in a port's queue."""
    return queue_limit_pkts(rate_mbps) * MTU_FRAME_B * 8 / (rate_mbps * 1e6)


def netem_limit_pkts(rate_mbps: float, delay_ms: float) -> int:
    """netem's limit also holds the packets "on the wire" during the delay: add rate x delay."""
    return queue_limit_pkts(rate_mbps) + math.ceil(rate_mbps * 1e6 * delay_ms / 1000 / (MTU_FRAME_B * 8))
