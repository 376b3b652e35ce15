"""Why each lost packet was lost, per link direction and window, and the random-loss test.

A direction's port loses a frame in one of two places (`emulation.shaping`): the random-loss
rule (nft `numgen`, in the bridge's forward hook, *before* the delay and the queue) or the tail
of the queue (pfifo full). The follower sees a frame leave switch i and never reach j; the FIFO
model (`fifo`) knows how full the queue was when it would have entered. Where the queue was full
the two causes look alike (a frame the loss rule took at that moment would have been tail-dropped
anyway), so the model alone over-counts tail drops and under-counts random ones. Where the run
logged the port's kernel counters for the window (`Counters`: HTB-sent, pfifo drops, loss-rule
drops) they settle it:

* **labels**: of the lost packets (forwarding changes apart: `TRANSITION`), exactly
  `queue_drops` are `TAIL`, those the model found at the fullest queue; up to `loss_drops` of the
  rest are `RANDOM`; any left over are `UNEXPLAINED`: the port did not drop them (a blackhole
  dropped them at the switch, a wormhole detour took them over another port, ...);
* **the random-loss test** (`LossStage`): the loss rule saw `offered = sent + queue_drops +
  loss_drops` frames and dropped `loss_drops`; the plan expects `offered x loss`.

Without counters (the netem backend, whose one drop count mixes both causes; runs made before
counters were logged) the model decides: a lost packet is `TAIL` when the model's queue was at
its limit (`QUEUE_FULL_SLACK`), else `RANDOM`, and the loss rule saw the crossings plus the
random losses.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .model import Counters

QUEUE_FULL_SLACK = 1  # a tail drop happens with the queue at its limit; allow one frame of model error

TAIL, RANDOM, TRANSITION, UNEXPLAINED = 0, 1, 2, 3


@dataclass(frozen=True)
class LossStage:
    """What one link direction's loss rule did in one window, and what the plan expected."""

    source: Literal["counters", "model"]
    offered: int  # frames that reached the loss rule
    dropped: int  # of those, dropped by it (random losses)
    planned_loss: float

    @property
    def expected(self) -> float:
        return self.offered * self.planned_loss

    @property
    def variance(self) -> float:
        return self.offered * self.planned_loss * (1.0 - self.planned_loss)


def counted(c: Counters | None) -> bool:
    """The counters tell tail drops from random ones (the HTB + nft backend logged them)."""
    return c is not None and None not in (c.sent_packets, c.queue_drops, c.loss_drops)


def classify(backlog: np.ndarray, limit: np.ndarray, transition: np.ndarray, crossed: int,
             counters: Counters | None, planned_loss: float) -> tuple[np.ndarray, LossStage]:
    """Labels of one link-window's lost packets (time order) and its loss stage.

    `backlog`: frames the model held when each would have entered the queue; `limit`: the queue
    limit then; `transition`: lost while forwarding changed; `crossed`: frames that got through.
    """
    labels = np.full(backlog.shape[0], TRANSITION, dtype=np.int8)
    cand = np.flatnonzero(~transition)
    if counted(counters):
        # fullest queue first; ties (a full queue) in time order
        by_fill = cand[np.lexsort((cand, limit[cand] - backlog[cand]))]
        n_tail = min(counters.queue_drops, by_fill.shape[0])
        n_random = min(counters.loss_drops, by_fill.shape[0] - n_tail)
        labels[by_fill[:n_tail]] = TAIL
        labels[by_fill[n_tail:n_tail + n_random]] = RANDOM
        labels[by_fill[n_tail + n_random:]] = UNEXPLAINED
        offered = counters.sent_packets + counters.queue_drops + counters.loss_drops
        return labels, LossStage("counters", offered, counters.loss_drops, planned_loss)
    full = backlog[cand] >= limit[cand] - QUEUE_FULL_SLACK
    labels[cand] = np.where(full, TAIL, RANDOM)
    n_random = int((~full).sum())
    return labels, LossStage("model", crossed + n_random, n_random, planned_loss)
