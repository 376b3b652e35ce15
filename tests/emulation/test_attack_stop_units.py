"""The executor's two-part stop: the family's `halt` at the event, the rest in a worker thread.

The family here is a stand-in plugin looked up in place of the registry's: what is tested is the
executor's ordering (records, waits, errors), not what a family does on the kernel (the root
tests drive the real floods and replayers through the same path)."""

from __future__ import annotations

import threading

import pytest

from helpers.runplans import attack, link, make_plan, nodes
from uavcas.emulation import attacks as attacks_mod
from uavcas.emulation.attacks import AttackError, AttackExecutor


class _SlowStop:
    """Halts at once; its bookkeeping waits for `release` (as a flood's counters wait for hping3)."""

    def __init__(self, fail: bool = False) -> None:
        self.release = threading.Event()
        self.calls: list[tuple[str, str]] = []
        self.fail = fail

    def start(self, ex, a):
        self.calls.append(("start", a.attack_id))
        return {}

    def halt(self, ex, a):
        self.calls.append(("halt", a.attack_id))

        def finish():
            assert self.release.wait(10.0)
            self.calls.append(("finish", a.attack_id))
            if self.fail:
                raise RuntimeError("counters unreadable")
            return {"t_unix": 1e9}

        return finish


@pytest.fixture
def setup(tmp_path, monkeypatch):
    fam = _SlowStop()
    monkeypatch.setattr(attacks_mod, "family", lambda name: fam)
    p = make_plan(nodes(4), [link("uav0", "bs0")],
                  [attack("blackhole", ["uav1"], "uav0", 0.0, 4.0, k=0),
                   attack("blackhole", ["uav1"], "uav0", 4.0, 8.0, k=1),  # same attacker
                   attack("blackhole", ["uav2"], "uav0", 4.0, 8.0, k=2)])  # another one
    return fam, p, AttackExecutor(object(), p, tmp_path, p.duration_s)


def test_halt_returns_before_the_bookkeeping_and_the_stop_record_follows_it(setup):
    fam, p, ex = setup
    ex.start(p.attacks[0])
    ex.halt(p.attacks[0])  # returns although finish() is blocked
    assert fam.calls == [("start", "blackhole-0"), ("halt", "blackhole-0")]
    assert [r.event for r in ex.records] == ["start"] and "blackhole-0" not in ex.active
    fam.release.set()
    ex.finish_all()
    assert [r.event for r in ex.records] == ["start", "stop"] and ex.records[1].t_unix == 1e9


def test_a_start_waits_only_for_stops_sharing_an_attacker(setup):
    fam, p, ex = setup
    ex.start(p.attacks[0])
    ex.halt(p.attacks[0])
    ex.start(p.attacks[2])  # uav2: does not wait (the first stop is still blocked)
    assert ("finish", "blackhole-0") not in fam.calls
    threading.Timer(0.2, fam.release.set).start()
    ex.start(p.attacks[1])  # uav1 again: waits until the first stop has finished
    assert fam.calls.index(("finish", "blackhole-0")) < fam.calls.index(("start", "blackhole-1"))
    assert [r.event for r in ex.records][-2:] == ["stop", "start"]
    ex.finish_all()


def test_stop_is_halt_and_finish(setup):
    fam, p, ex = setup
    fam.release.set()
    ex.start(p.attacks[0])
    rec = ex.stop(p.attacks[0])
    assert rec.event == "stop" and rec.attack_id == "blackhole-0" and ex.records[-1] is rec
    assert ex.stop(p.attacks[0]) is None  # not active any more


def test_errors_of_the_bookkeeping_surface(setup):
    fam, p, ex = setup
    fam.fail = True
    fam.release.set()
    ex.start(p.attacks[0])
    ex.halt(p.attacks[0])
    with pytest.raises(AttackError, match="blackhole-0: stop failed: counters unreadable"):
        ex.finish_all()
    ex.start(p.attacks[2])
    ex.halt(p.attacks[2])
    ex.stop_all()  # the end of a run keeps going and keeps the error
    assert ex.errors == ["blackhole-2: stop failed: counters unreadable"]
