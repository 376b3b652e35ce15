"""Self-measurement on a two-hop test path (used by `uavcas doctor` and the tests).

Topology: uav0 - uav1 - uav2 (line), so traffic uav0 -> uav2 crosses two shaped switch links.
Measured end to end with small Python endpoints started inside the namespaces:
* TCP goodput (bulk transfer, slow start discarded) vs the configured rate x 1448/1514
  (HTB counts Ethernet frames of 1514 B carrying 1448 B of TCP payload with timestamps);
* one-way delay of UDP probes (all namespaces share one clock: the send time against the
  kernel's receive timestamp) vs the sum of the hops' delays: median, p90 and p99;
* UDP loss vs 1 - prod(1 - loss_hop), judged against the binomial 99 % interval.

Endpoints: python -m uavcas.diagnostics.selftest {tcp-sink,tcp-source,udp-sink,udp-source} ...
"""

from __future__ import annotations

import argparse
import json
import socket
import struct
import subprocess
import sys
import time

PORT = 5999
SO_TIMESTAMPNS = 35  # = SCM_TIMESTAMPNS (asm-generic/socket.h); not exported by Python's socket


# endpoints (run inside namespaces) -----------------------------------------------------------
def tcp_sink(port: int, seconds: float) -> dict:
    srv = socket.socket()
    srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    srv.bind(("0.0.0.0", port))
    srv.listen(1)
    srv.settimeout(seconds + 5)
    print("ready", flush=True)
    conn, _ = srv.accept()
    conn.settimeout(seconds + 5)
    samples = []
    total = 0
    buf = bytearray(65536)
    while True:
        n = conn.recv_into(buf)
        if not n:
            break
        total += n
        samples.append((time.monotonic(), total))
    if len(samples) < 2:
        return {"bytes": total, "goodput_mbps": 0.0}
    t0 = samples[0][0] + min(0.5, (samples[-1][0] - samples[0][0]) / 3)  # skip slow start
    first = next(s for s in samples if s[0] >= t0)
    last = samples[-1]
    secs = last[0] - first[0]
    return {"bytes": total, "seconds": secs, "goodput_mbps": (last[1] - first[1]) * 8 / secs / 1e6 if secs else 0.0}


def tcp_source(dst: str, port: int, seconds: float) -> dict:
    s = socket.create_connection((dst, port), timeout=5)
    chunk = b"\0" * 65536
    end = time.monotonic() + seconds
    sent = 0
    while time.monotonic() < end:
        sent += s.send(chunk)
    s.close()
    return {"sent": sent}


_END_MARKER = 2**64 - 1  # sequence number of the probe stream's last datagram


def udp_sink(port: int, count: int, seconds: float) -> dict:
    """Receives the probes; a probe's delay is the kernel's receive timestamp (SO_TIMESTAMPNS,
    taken when the frame reaches this namespace's eth0) minus its send time, so this process's
    own scheduling latency is not counted (it was 0.1-3 ms of every figure on a busy machine)."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
    s.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
    s.bind(("0.0.0.0", port))
    print("ready", flush=True)
    seen = set()
    delays = []
    deadline = time.monotonic() + seconds
    draining = False
    anc_size = socket.CMSG_SPACE(16)
    while len(seen) < count:
        left = deadline - time.monotonic()
        if left <= 0:
            break
        s.settimeout(max(0.001, left))
        try:
            data, anc, _, _ = s.recvmsg(2048, anc_size)
        except socket.timeout:
            break
        now = kernel_rx_ns(anc)
        seq, sent_ns = struct.unpack_from("!QQ", data)
        if seq == _END_MARKER:
            if not draining:  # probes still held by the delay stage get 0.3 s more, then stop
                draining, deadline = True, time.monotonic() + 0.3
            continue
        if seq not in seen:
            seen.add(seq)
            delays.append((now - sent_ns) / 1e6)
    return {"received": len(seen), "delays_ms": _summary(delays)}


def kernel_rx_ns(ancillary: list[tuple[int, int, bytes]]) -> int:
    """CLOCK_REALTIME ns of the SCM_TIMESTAMPNS message (now, if the kernel attached none)."""
    for level, kind, data in ancillary:
        if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS and len(data) >= 16:
            sec, nsec = struct.unpack_from("@qq", data)
            return sec * 1_000_000_000 + nsec
    return time.time_ns()


def percentile(sorted_xs: list[float], q: float) -> float:
    """Linear-interpolated percentile (numpy's default) of a sorted list: stdlib only, because
    every endpoint imports this module and a slow guest pays each import dearly."""
    pos = (len(sorted_xs) - 1) * q / 100
    lo = int(pos)
    hi = min(lo + 1, len(sorted_xs) - 1)
    return sorted_xs[lo] + (sorted_xs[hi] - sorted_xs[lo]) * (pos - lo)


def _summary(xs: list[float]) -> dict:
    if not xs:
        return {}
    a = sorted(xs)
    return {"median": percentile(a, 50), "p90": percentile(a, 90), "p99": percentile(a, 99), "min": a[0],
            "max": a[-1], "mean": sum(a) / len(a)}


def udp_source(dst: str, port: int, count: int, pps: float, size: int) -> dict:
    """Paced sender: every millisecond it sends the probes that are due (no busy spin, so it
    leaves the CPU to the stage under test on a 2-core machine)."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4 << 20)
    pad = b"\0" * max(0, size - 16)
    start = time.monotonic()
    seq = 0
    while seq < count:
        due_now = min(count, int((time.monotonic() - start) * pps) + 1)
        while seq < due_now:
            try:
                s.sendto(struct.pack("!QQ", seq, time.time_ns()) + pad, (dst, port))
            except BlockingIOError:
                break
            seq += 1
        time.sleep(0.001)
    elapsed = time.monotonic() - start
    time.sleep(0.05)
    for _ in range(3):
        s.sendto(struct.pack("!QQ", _END_MARKER, 0), (dst, port))
    return {"sent": count, "seconds": elapsed, "offered_pps": count / elapsed if elapsed else 0.0}


# orchestration (from the parent, through an Emulation) -----------------------------------------
def _endpoint(emu, node: str, args: list[str], timeout_s: float) -> subprocess.Popen:
    return emu.popen(node, [sys.executable, "-m", "uavcas.diagnostics.selftest", *args], timeout_s=timeout_s,
                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_ready(p: subprocess.Popen) -> None:
    line = p.stdout.readline()
    if line.strip() != "ready":
        raise RuntimeError(f"selftest endpoint failed: {p.stderr.read()[-500:]}")


def _result(p: subprocess.Popen, timeout_s: float) -> dict:
    out, err = p.communicate(timeout=timeout_s)
    lines = [ln for ln in out.splitlines() if ln.startswith("{")]
    if p.returncode != 0 or not lines:
        raise RuntimeError(f"selftest endpoint rc {p.returncode}: {err[-500:]}")
    return json.loads(lines[-1])


def measure_goodput(emu, src: str, dst: str, seconds: float = 2.5, startup_s: float = 10.0) -> float:
    """`startup_s`: how long an endpoint may take to start (an emulated CPU needs a minute)."""
    wait = seconds + startup_s
    sink = _endpoint(emu, dst, ["tcp-sink", "--port", str(PORT), "--seconds", str(wait)], 2 * wait)
    _wait_ready(sink)
    source = _endpoint(emu, src, ["tcp-source", "--dst", emu.ip(dst), "--port", str(PORT), "--seconds",
                                  str(seconds)], 2 * wait)
    _result(source, 2 * wait)
    return _result(sink, 2 * wait)["goodput_mbps"]


def measure_udp(emu, src: str, dst: str, count: int, pps: float, size: int = 200, startup_s: float = 5.0) -> dict:
    secs = count / pps + startup_s
    sink = _endpoint(emu, dst, ["udp-sink", "--port", str(PORT + 1), "--count", str(count),
                                "--seconds", str(secs)], secs + 10 + startup_s)
    _wait_ready(sink)
    source = _endpoint(emu, src, ["udp-source", "--dst", emu.ip(dst), "--port", str(PORT + 1), "--count",
                                  str(count), "--pps", str(pps), "--size", str(size)], secs + 10 + startup_s)
    sent = _result(source, secs + 10 + startup_s)
    got = _result(sink, secs + 10 + startup_s)
    return {**got, **sent, "loss": 1 - got["received"] / count}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["tcp-sink", "tcp-source", "udp-sink", "udp-source"])
    ap.add_argument("--dst")
    ap.add_argument("--port", type=int, default=PORT)
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--count", type=int, default=1000)
    ap.add_argument("--pps", type=float, default=1000)
    ap.add_argument("--size", type=int, default=200)
    a = ap.parse_args(argv)
    if a.mode == "tcp-sink":
        res = tcp_sink(a.port, a.seconds)
    elif a.mode == "tcp-source":
        res = tcp_source(a.dst, a.port, a.seconds)
    elif a.mode == "udp-sink":
        res = udp_sink(a.port, a.count, a.seconds)
    else:
        res = udp_source(a.dst, a.port, a.count, a.pps, a.size)
    print(json.dumps(res), flush=True)


if __name__ == "__main__":
    main()
