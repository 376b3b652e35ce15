"""The flood tool (`attacks/tools/flood.py`) without root: its rules, nft texts and its pacer (`pacer.py`)."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import threading
import time

import pytest

from uavcas.attacks.tools import flood, pacer, tool_path


def test_flood_pacing_interval_rules_and_quiet_time():
    assert flood.pace_interval_us(1000) == 1000
    assert flood.pace_interval_us(1e6) == flood.PACE_FLOOR_US  # never faster than the floor
    rs = flood.counter_ruleset("uavcas_f_dos_0", "10.9.0.2", 80)
    assert "hook postrouting" in rs and 'oifname "eth0" ip daddr 10.9.0.2 tcp dport 80' in rs
    assert "(syn | ack) == syn" in rs and "type route hook output" in rs
    gate = flood.gate_rule("uavcas_f_dos_0", "10.9.0.2", 80, 0x5CA10001)
    assert gate.startswith("add rule ip uavcas_f_dos_0 gate ") and "meta mark set 0x5ca10001" in gate
    lines = flood.gate_lines(3, 0x5CA10003, 20003)
    assert "link add fg3a type veth peer name fg3b" in lines and "route add default dev fg3a table 20003" in lines
    js = ('{"nftables": [{"metainfo": {}}, {"counter": {"family": "ip", "name": "syn", "packets": 42, "bytes": 1}},'
          ' {"counter": {"family": "ip", "name": "gated", "packets": 1, "bytes": 1}}]}')
    assert flood.parse_counters(js) == {"syn": 42, "gated": 1}
    assert flood.table_name("ddos-1") == "uavcas_f_ddos_1"
    # 2 hops of 2 ms at 10 Mbit/s: delays + two full 50 ms queues (42 frames each) + slack
    q = flood.quiet_after_s([(2.0, 10.0), (2.0, 10.0)])
    assert q == pytest.approx(0.004 + 2 * 42 * 1514 * 8 / 10e6 + flood.QUIET_SLACK_S)
    assert flood.quiet_after_s([]) == flood.QUIET_SLACK_S


_ALARM_COUNTER = r"""
import signal, sys, time
# counts each delivery as the kernel makes it (a Python handler would merge two that arrive
# before it runs; hping3's C handler sends one SYN per delivery)
sigs = {signal.SIGALRM, signal.SIGTERM}
signal.pthread_sigmask(signal.SIG_BLOCK, sigs)
print("up", flush=True)
stall_at, stall = time.monotonic() + 0.2, float(sys.argv[1])
n = 0
while True:
    if stall and time.monotonic() >= stall_at:
        time.sleep(stall)  # a starved hping3: the signal stays pending meanwhile
        stall = 0
    info = signal.sigtimedwait(sigs, 0.01)
    if info is None:
        continue
    if info.si_signo == signal.SIGTERM:
        print(n, flush=True)
        sys.exit(0)
    n += 1
"""


def test_pacer_never_loses_a_signal_and_catches_up_after_a_stall():
    """Each SIGALRM is one SYN: none may be merged into a pending one, and after a stall the
    pacer makes up the missed ones (the rate holds however late anything wakes up)."""
    child = subprocess.Popen([sys.executable, "-c", _ALARM_COUNTER, "0.1"], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "up"
    r, w = os.pipe()
    out = io.StringIO()
    th = threading.Thread(target=lambda: out.write(json.dumps(pacer.pace(child.pid, 500.0, r, io.StringIO()))))
    th.start()
    os.write(w, b"go\n")
    time.sleep(0.8)
    os.write(w, b"stop\n")
    th.join(10)
    child.terminate()
    received = int(child.communicate(timeout=10)[0].split()[-1])
    rep = json.loads(out.getvalue())
    assert rep["signals"] == received  # no signal lost while one was pending
    assert rep["max_behind"] >= 30  # the 0.1 s stall was seen ...
    assert rep["signals"] >= 500 * rep["seconds"] - 10  # ... and made up by the end
    os.close(r)
    os.close(w)



def test_the_pacer_starts_by_its_path_and_loads_no_uavcas_module(tmp_path):
    """Run as the flood runs it (by its path): it says ready and, on EOF before "go", reports that
    it sent nothing; it imports no module of uavcas (no package's start-up before t0)."""
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    argv = [str(tool_path("pacer")), "--pid", str(child.pid), "--pps", "100"]
    try:
        r = subprocess.run([sys.executable, "-X", "importtime", *argv], input="", capture_output=True, text=True,
                           timeout=30, cwd=tmp_path)
    finally:
        child.kill()
        child.wait(10)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "ready" and json.loads(lines[-1]) == {"signals": 0, "seconds": 0.0, "max_behind": 0}
    imported = [line.rsplit("|", 1)[-1].strip() for line in r.stderr.splitlines() if line.startswith("import time:")]
    assert "json" in imported and not [m for m in imported if m.split(".")[0] == "uavcas"]
