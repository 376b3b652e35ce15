"""Unit tests of the attack tools and the capture (no root): pacing, parsers, the replay logic.
(The benign apps' are in tests/traffic.)"""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import threading
import time

import pytest
from scapy.layers.inet import IP, TCP, UDP
from scapy.layers.l2 import Ether

from uavcas import seeding
from uavcas.emulation.apps import capture, flood, replayer


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
    th = threading.Thread(target=lambda: out.write(json.dumps(flood.pace(child.pid, 500.0, r, io.StringIO()))))
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


def test_capture_stats_parse():
    err = ("tcpdump: listening on s0\n1234 packets captured\n1240 packets received by filter\n"
           "6 packets dropped by kernel\n")
    assert capture.parse_stats(err) == {"captured": 1234, "received by filter": 1240, "dropped by kernel": 6}
    argv = capture.argv("s3", capture.Path("/x/s-uav3.pcap"))
    assert "-p" not in argv and "-U" in argv and argv[argv.index("-Z") + 1] == "root"
    assert capture.point_name("uav3") == "s-uav3"


def _frame(src="10.9.0.3", dst="10.9.0.9", ttl=64, seq=1000, ip_id=7, payload=b"x" * 100) -> bytes:
    return bytes(Ether(src="02:00:00:00:00:03", dst="02:00:00:00:00:09") / IP(src=src, dst=dst, ttl=ttl, id=ip_id)
                 / TCP(sport=80, dport=40000, seq=seq, flags="PA") / payload)


def test_replay_parse_and_mutate_seq_modes():
    s = replayer.parse(_frame())
    assert (s.src, s.dst, s.proto, s.sport, s.dport, s.ip_id, s.ttl, s.seq) == (
        "10.9.0.3", "10.9.0.9", 6, 80, 40000, 7, 64, 1000)
    rng = seeding.generator(1, "replayer", 0)
    out, seq = replayer.mutate(_frame(), 3, "inc", 5, rng)
    p = Ether(out)
    assert p[IP].ttl == 59 and p[TCP].seq == 1003 == seq and p[IP].id == 7
    assert IP(bytes(p[IP])).chksum == Ether(bytes(p))[IP].chksum  # valid checksum after rebuild
    rebuilt = Ether(out)
    del rebuilt[IP].chksum
    del rebuilt[TCP].chksum
    assert Ether(bytes(rebuilt))[TCP].chksum == p[TCP].chksum
    assert replayer.mutate(_frame(), 3, "zero", 5, rng)[1] == 1000
    assert replayer.new_seq(0xFFFFFFFF, 2, "inc", rng) == 1
    seqs = {replayer.mutate(_frame(), 1, "rand", 3, rng)[1] for _ in range(5)}
    assert len(seqs) == 5
    udp = bytes(Ether() / IP(src="10.9.0.3", dst="10.9.0.1", ttl=64) / UDP(sport=1, dport=2) / b"hi")
    out, seq = replayer.mutate(udp, 1, "inc", 5, rng)
    assert seq is None and Ether(out)[IP].ttl == 59


def test_replayer_buffers_victim_traffic_paces_and_never_replays_itself():
    r = replayer.Replayer("10.9.0.3", "10.9.0.5", buffer_pkts=3, delay_ms=200, rate_pps=10, ttl_dec=5,
                          seq_mode="inc")
    assert not r.observe(0.0, _frame(src="10.9.0.7", dst="10.9.0.8"))  # not the victim's
    assert not r.observe(0.0, _frame(src="10.9.0.5", dst="10.9.0.3"))  # the attacker's own
    assert not r.observe(0.0, _frame(), outgoing=True)  # what we sent ourselves
    for k in range(5):
        assert r.observe(0.01 * k, _frame(ip_id=k, seq=1000 + k)) == (k < 3)
    assert len(r.buffer) == 3 and r.stats["buffer_full"] == 2  # a full buffer admits nothing new
    assert not r.due(0.1)  # not before the delay
    assert r.due(0.25)
    out, rec = r.next_injection(0.25)
    assert rec["ip_id"] == 0 and rec["ttl"] == 59 and rec["seq"] == 1000 + 1 and rec["orig_seq"] == 1000
    assert not r.due(0.26)  # paced: next one 100 ms later
    assert r.due(0.36)
    assert r.observe(0.3, _frame(ip_id=10, seq=2000))  # a slot was freed
    assert not r.observe(0.3, out)  # our injection coming back through the mirror
    assert not r.observe(0.3, _frame(ttl=59, ip_id=99))  # a TTL only our injections carry
    assert r.stats["own_ignored"] == 2
    _, rec2 = r.next_injection(0.36)
    assert rec2["seq"] == 1001 + 2  # k counts injections


def test_replayer_buffers_and_replays_a_udp_stream_with_ip_id_0_and_the_ttl_kept():
    """MAVLink from an unconnected socket: IP id 0 on every datagram. With ttl_dec 0 only the bytes
    tell our copy (coming back through the mirror) from the stream's next datagram."""
    def mav(seq: int) -> bytes:
        return bytes(Ether() / IP(src="10.9.0.3", dst="10.9.1.1", ttl=64, id=0)
                     / UDP(sport=14555, dport=14550) / (bytes([0xFD, 9, 0, 0, seq, 1, 1, 0, 0, 0]) + bytes(11)))

    r = replayer.Replayer("10.9.0.3", "10.9.0.5", buffer_pkts=5, delay_ms=0, rate_pps=100, ttl_dec=0,
                          seq_mode="inc")
    assert r.observe(0.0, mav(0))
    out, rec = r.next_injection(0.0)
    assert (rec["protocol"], rec["src_port"], rec["dst_port"], rec["ip_id"], rec["ttl"], rec["seq"]) == (
        17, 14555, 14550, 0, 64, None)
    assert Ether(out)[UDP].payload.load == Ether(mav(0))[UDP].payload.load  # the datagram as it was
    assert not r.observe(0.01, out)  # our copy, back through the mirror
    assert r.observe(0.1, mav(1))  # the stream's next datagram: same header fields, other bytes
    assert r.stats["own_ignored"] == 1 and r.stats["buffered"] == 2
