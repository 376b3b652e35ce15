"""Lost packets split into queue-tail, random, transition and unexplained (fidelity.losses), by hand."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.fidelity import losses
from uavcas.fidelity.losses import RANDOM, TAIL, TRANSITION, UNEXPLAINED
from uavcas.fidelity.model import Counters

# six lost packets in time order: the model's backlog when each would have entered a queue of 10
BACKLOG = np.array([10, 3, 10, 9, 0, 5])
LIMIT = np.full(6, 10)
TRANS = np.array([False, False, False, False, True, False])  # the fifth: during a forwarding change


def _classify(counters, crossed=100, p=0.02):
    return losses.classify(BACKLOG, LIMIT, TRANS, crossed, counters, p)


def test_counters_set_how_many_are_tail_and_random_drops():
    labels, stage = _classify(Counters(sent_packets=100, queue_drops=2, loss_drops=2, link_drops=0))
    # fullest queue first (room 0, 0, 1, 5, 7; ties in time order): packets 0 and 2 are the two
    # tail drops, 3 and 5 the two random ones, 1 is more than the port dropped
    assert labels.tolist() == [TAIL, UNEXPLAINED, TAIL, RANDOM, TRANSITION, RANDOM]
    assert (stage.source, stage.offered, stage.dropped) == ("counters", 104, 2)
    assert stage.expected == pytest.approx(104 * 0.02) and stage.variance == pytest.approx(104 * 0.02 * 0.98)


def test_counted_drops_beyond_the_followed_losses_still_enter_the_loss_test():
    # the kernel dropped traffic the follower never saw (not every frame is followed): the labels
    # run out, the loss stage keeps the kernel's figures
    labels, stage = _classify(Counters(sent_packets=500, queue_drops=1, loss_drops=10))
    assert labels.tolist() == [TAIL, RANDOM, RANDOM, RANDOM, TRANSITION, RANDOM]
    assert (stage.offered, stage.dropped) == (511, 10)
    labels, _ = _classify(Counters(sent_packets=500, queue_drops=9, loss_drops=0))
    assert labels.tolist() == [TAIL, TAIL, TAIL, TAIL, TRANSITION, TAIL]


def test_random_drops_at_a_full_queue_are_random_when_the_counters_say_so():
    labels, stage = _classify(Counters(sent_packets=100, queue_drops=0, loss_drops=5))
    assert labels.tolist() == [RANDOM, RANDOM, RANDOM, RANDOM, TRANSITION, RANDOM]
    assert stage.dropped == 5 and stage.offered == 105


@pytest.mark.parametrize("counters", [None, Counters(sent_packets=None, queue_drops=4, loss_drops=None, link_drops=0),
                                      Counters(link_drops=3)])
def test_without_full_counters_the_model_decides(counters):
    # netem's one drop count, or none: tail where the model's queue was within one frame of its limit
    assert not losses.counted(counters)
    labels, stage = _classify(counters, crossed=100)
    assert labels.tolist() == [TAIL, RANDOM, TAIL, TAIL, TRANSITION, RANDOM]
    assert (stage.source, stage.offered, stage.dropped) == ("model", 102, 2)


def test_no_losses():
    labels, stage = losses.classify(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, bool), 50,
                                    Counters(sent_packets=50, queue_drops=0, loss_drops=0), 0.1)
    assert labels.shape == (0,) and (stage.offered, stage.dropped) == (50, 0)
