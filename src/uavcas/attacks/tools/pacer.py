"""The flood's pacer: SIGALRM to one hping3 at absolute deadlines, one signal per SYN (see `flood`).

A process of its own per hping3, started by `flood.Flood.prepare` before t0; it says `ready`, waits
for `go` on stdin, paces until `stop`, EOF or the end of hping3, and prints what it did as one
JSON line. It imports nothing but the standard library, and the flood starts it by this file's
path (`tool_path("pacer")`, as every tool: the package's docstring says why).

Run: python .../uavcas/attacks/tools/pacer.py --pid PID --pps RATE [--ns NAME]
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import select
import signal
import sys
import time

PACE_FLOOR_US = 100  # at most 10,000 SYN/s per attacker: each SYN costs hping3 + pacer a wake-up
PRIORITY_NICE = -10  # hping3 and its pacer (see Flood.prepare)
_SIGALRM_BIT = 1 << (signal.SIGALRM - 1)
_PR_SET_TIMERSLACK = 29


def _alarm_pending(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith(("ShdPnd:", "SigPnd:")) and int(line.split()[1], 16) & _SIGALRM_BIT:
                    return True
    except OSError:
        return False
    return False


def pace(pid: int, pps: float, commands: int = 0, out=None) -> dict:
    """Wait for "go" on fd `commands`, then SIGALRM `pid` at t_go + k / pps until "stop", EOF
    or the end of `pid`. Returns what it did (signals, seconds from go, most SYNs behind)."""
    out = out or sys.stdout
    fd = os.pidfd_open(pid)
    floor_s = PACE_FLOOR_US / 1e6
    print("ready", file=out, flush=True)
    if os.read(commands, 64).strip() != b"go":
        return {"signals": 0, "seconds": 0.0, "max_behind": 0}
    t0 = time.monotonic()
    sent, max_behind, last = 0, 0, float("-inf")
    while True:
        now = time.monotonic()
        due = int((now - t0) * pps) + 1  # the first SYN at t0
        max_behind = max(max_behind, due - sent - 1)
        if sent < due and now - last >= floor_s and not _alarm_pending(pid):
            try:
                signal.pidfd_send_signal(fd, signal.SIGALRM)
            except ProcessLookupError:
                break
            sent, last = sent + 1, now
        # still behind (late wake-up, or hping3 had not taken the last signal): retry one floor
        # interval on; else sleep to the next deadline
        if sent < int((time.monotonic() - t0) * pps) + 1:
            wait = floor_s
        else:
            wait = t0 + sent / pps - time.monotonic()
        ready, _, _ = select.select([commands, fd], [], [], max(0.0, wait))
        if ready:
            break  # "stop", EOF, or hping3 exited (its pidfd is readable)
    return {"signals": sent, "seconds": time.monotonic() - t0, "max_behind": max_behind}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="pacer.py",
                                 description="SIGALRM pacer for one hping3 (see uavcas.attacks.tools.flood)")
    ap.add_argument("--pid", type=int, required=True)
    ap.add_argument("--pps", type=float, required=True)
    ap.add_argument("--ns", help="the attacker's namespace (informational)")
    a = ap.parse_args(argv)
    ctypes.CDLL(None).prctl(_PR_SET_TIMERSLACK, 1, 0, 0, 0)  # deadlines to the microsecond, not 50 us
    try:
        os.setpriority(os.PRIO_PROCESS, 0, PRIORITY_NICE)  # a wake-up in time matters more than CPU share
    except OSError:
        pass
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    print(json.dumps(pace(a.pid, a.pps)), flush=True)


if __name__ == "__main__":  # run by its path (uavcas.attacks.tools.tool_path)
    main()
