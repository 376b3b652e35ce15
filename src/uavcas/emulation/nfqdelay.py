"""Userspace per-port delay stage: an NFQUEUE client holding verdicts.

This kernel has no netem (nor fq/etf for EDT), so propagation delay is added in userspace:
`iptables -A FORWARD -m physdev --physdev-out l+ -j NFQUEUE --queue-bypass` in the fabric
namespace sends every bridged IPv4 frame leaving a switch-to-switch port here; the daemon reads
metadata and the IP header's first word (copy range 4: the packet's length), looks the delay up
by the *physical out port* (NFQA_IFINDEX_PHYSOUTDEV, i.e. the link direction) and accepts the
packet when it is due.

Two implementations, one protocol: the compiled verdict loop `nfqdelay.c` (built on first use
with the system C compiler, cached beside the interpreter; `python -m uavcas.emulation.nfqdelay
--build` builds it ahead) and this module's pure-Python loop, used when no compiler is there
(`--impl python` or UAVCAS_DELAY_IMPL=python forces it). `main` execs the helper, so the daemon's PID
stays the one the shaper started. What both do to hold delay (issue #14, EMULATION-NOTES sec. 2):
* due = the packet's kernel receive stamp (NFQA_TIMESTAMP: the stamp the switch captures carry;
  a socket with SO_TIMESTAMP turns stamping on) + the port's delay, so softirq and socket
  backlog before the daemon runs do not add to the delay;
* due packets are released between receive batches (a burst never holds a release back), all
  verdicts due together in one netlink write;
* a timerfd armed at absolute CLOCK_MONOTONIC deadlines (Python's epoll timeout is millisecond
  granular), PR_SET_TIMERSLACK 1 ns;
* SCHED_FIFO priority `--rt` for the helper (the kernel's RT throttling, 95 % of a period, keeps
  a runaway from freezing the machine), else nice -15.
* pacing: a port given a rate (`set NAME=US,RATE_BPS,BURST_B,LIMIT_PKTS`) also serves its frames
  FIFO through a token bucket in virtual time, the fidelity audit's link model
  (`uavcas.fidelity.fifo`), and releases each at its start; the queue tail is dropped at the
  limit. HTB alone refills only a one-frame bucket while the host is frozen, so a backlogged
  link stayed late by the freeze for the rest of its busy period (nfqdelay.c says more).
Fail-open: if the queue overflows the kernel accepts instead of dropping, and `--queue-bypass`
passes packets undelayed if the daemon dies.

Control: a UNIX stream socket; one request line per connection, one JSON line back:
  set l0-1=5000 l1-0=5000,270000,1600,16 ...
                                -> {"ok": true, "table": {"l0-1": 5000, ...}, "pacing": {...}}
      (delay in microseconds; optionally rate bit/s, bucket bytes, queue limit frames;
       "pacing": {port: [rate_bps, burst_b, limit_pkts, frames paced, tail drops]})
  get                           -> {"ok": true, "table": ..., "stats": {...}}
  stop                          -> {"ok": true}
`request(path, {"op": "set", "delays_us": {...}, "pacing": {port: Pacing}})` speaks it from Python.
Run: python -m uavcas.emulation.nfqdelay --queue 0 --ctl PATH  (inside the fabric namespace)
"""

from __future__ import annotations

import argparse
import ctypes
import errno
import gc
import heapq
import json
import os
import select
import signal
import socket
import struct
import time

from .delayhelper import build_helper
from .pacing import PacedPort, Pacing
from .priority import DELAY_RT_PRIORITY

NETLINK_NETFILTER = 12
NFNL_SUBSYS_QUEUE = 3
NFQNL_MSG_PACKET, NFQNL_MSG_VERDICT, NFQNL_MSG_CONFIG = 0, 1, 2
NFQA_PACKET_HDR, NFQA_VERDICT_HDR, NFQA_TIMESTAMP, NFQA_IFINDEX_PHYSOUTDEV = 1, 2, 4, 8
NFQA_PAYLOAD, NFQA_CAP_LEN = 10, 16
NFQA_CFG_CMD, NFQA_CFG_PARAMS, NFQA_CFG_QUEUE_MAXLEN, NFQA_CFG_MASK, NFQA_CFG_FLAGS = 1, 2, 3, 4, 5
NFQNL_CFG_CMD_BIND = 1
NFQNL_COPY_PACKET = 2
COPY_RANGE = 4  # the IPv4 header's first word: the kernel then also sends NFQA_CAP_LEN, the packet's length
NFQA_CFG_F_FAIL_OPEN = 1
NF_DROP, NF_ACCEPT = 0, 1
ETH_HLEN = 14  # NFQUEUE's length is the IP packet's; captures and the model count the Ethernet frame
NLM_F_REQUEST, NLM_F_ACK = 1, 4
NLMSG_ERROR = 2
CLOCK_MONOTONIC, TFD_TIMER_ABSTIME = 1, 1
TFD_NONBLOCK, TFD_CLOEXEC = 0o4000, 0o2000000
PR_SET_TIMERSLACK = 29
SO_TIMESTAMP = 29  # asm-generic/socket.h (Python's socket module does not export it)
LAG_BUCKETS_US = (25, 50, 100, 200, 500, 1000, 2000, 5000, 10000, 10**9)
IMPL_ENV = "UAVCAS_DELAY_IMPL"  # auto | c | python: which verdict loop a daemon started by a shaper runs
# Released this much before due: the verdict's own path (reinjection, rate stage, veth) until
# the next switch stamps the frame, measured here at ~10-20 us.
DEFAULT_LEAD_US = 10


class _Timespec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


class _Itimerspec(ctypes.Structure):
    _fields_ = [("it_interval", _Timespec), ("it_value", _Timespec)]


_libc = ctypes.CDLL(None, use_errno=True)


def _attr(kind: int, payload: bytes) -> bytes:
    length = 4 + len(payload)
    return struct.pack("=HH", length, kind) + payload + b"\0" * ((4 - length % 4) % 4)


def _msg(msg_type: int, flags: int, queue: int, attrs: bytes, seq: int = 0) -> bytes:
    body = struct.pack("=BB", socket.AF_UNSPEC, 0) + struct.pack("!H", queue) + attrs
    return struct.pack("=IHHII", 16 + len(body), (NFNL_SUBSYS_QUEUE << 8) | msg_type, flags, seq, 0) + body


def verdict_msg(queue: int, packet_id: int, verdict: int = NF_ACCEPT) -> bytes:
    return _msg(NFQNL_MSG_VERDICT, NLM_F_REQUEST, queue,
                _attr(NFQA_VERDICT_HDR, struct.pack("!II", verdict, packet_id)))


def _bucket(hist: list[int], lag_us: float) -> None:
    for k, edge in enumerate(LAG_BUCKETS_US):
        if lag_us <= edge:
            hist[k] += 1
            return


class DelayDaemon:
    """The pure-Python verdict loop (the fallback of the compiled helper; same protocol)."""

    def __init__(self, queue: int, ctl_path: str, maxlen: int = 65536, lead_us: float = DEFAULT_LEAD_US) -> None:
        self.queue = queue
        self.lead_ns = int(lead_us * 1000)
        self.delay_ns: dict[int, int] = {}  # physoutdev ifindex -> delay
        self.table_us: dict[str, int] = {}  # port name -> delay, as applied
        self.heap: list[tuple[int, int]] = []  # (due_ns, packet_id)
        self.paced: dict[int, PacedPort] = {}  # ifindex -> its pacing (ports given a rate)
        self.paced_names: dict[str, int] = {}
        self.packets = self.unknown_port = self.overflows = self.kernel_ts = 0
        self.lag_hist = [0] * len(LAG_BUCKETS_US)
        self.recv_hist = [0] * len(LAG_BUCKETS_US)
        self.max_lag_us = 0.0
        # one socket asking for receive stamps turns stamping on for every packet, kernel-wide
        self.ts_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.ts_sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMP, 1)
        self.nl = socket.socket(socket.AF_NETLINK, socket.SOCK_RAW, NETLINK_NETFILTER)
        self.nl.setsockopt(socket.SOL_SOCKET, 33, 8 << 20)  # SO_RCVBUFFORCE: absorb bursts
        self.nl.bind((0, 0))
        self._configure(maxlen)
        self.nl.setblocking(False)
        self.tfd = _libc.timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC)
        if self.tfd < 0:
            raise OSError(ctypes.get_errno(), "timerfd_create")
        if os.path.exists(ctl_path):
            os.unlink(ctl_path)
        self.ctl = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.ctl.bind(ctl_path)
        self.ctl.listen(16)
        self.ctl.setblocking(False)
        self.running = True

    def _request(self, msg: bytes) -> None:
        self.nl.send(msg)
        reply = self.nl.recv(65536)
        _, kind = struct.unpack_from("=IH", reply)
        if kind == NLMSG_ERROR:
            (code,) = struct.unpack_from("=i", reply, 16)
            if code != 0:
                raise OSError(-code, f"nfqueue config: {os.strerror(-code)}")

    def _configure(self, maxlen: int) -> None:
        cfg = NLM_F_REQUEST | NLM_F_ACK
        self._request(_msg(NFQNL_MSG_CONFIG, cfg, self.queue,
                           _attr(NFQA_CFG_CMD, struct.pack("!BxH", NFQNL_CFG_CMD_BIND, socket.AF_INET))))
        self._request(_msg(NFQNL_MSG_CONFIG, cfg, self.queue,
                           _attr(NFQA_CFG_PARAMS, struct.pack("!IB", COPY_RANGE, NFQNL_COPY_PACKET))
                           + _attr(NFQA_CFG_QUEUE_MAXLEN, struct.pack("!I", maxlen))
                           + _attr(NFQA_CFG_MASK, struct.pack("!I", NFQA_CFG_F_FAIL_OPEN))
                           + _attr(NFQA_CFG_FLAGS, struct.pack("!I", NFQA_CFG_F_FAIL_OPEN))))

    # packets -----------------------------------------------------------------------------
    def _on_packets(self, out: list[bytes]) -> None:
        for k in range(512):
            try:
                data = self.nl.recv(65536)
            except BlockingIOError:
                return
            except OSError as e:
                if e.errno == errno.ENOBUFS:  # the kernel could not deliver: it failed open
                    self.overflows += 1
                    continue
                raise
            now = time.monotonic_ns()
            real_minus_mono = time.time_ns() - now
            off = 0
            while off + 16 <= len(data):
                length, kind = struct.unpack_from("=IH", data, off)
                if length < 16:
                    break
                if kind == (NFNL_SUBSYS_QUEUE << 8) | NFQNL_MSG_PACKET:
                    self._on_packet(data, off + 20, off + length, now, real_minus_mono, out)
                off += (length + 3) & ~3
            if k % 16 == 15:
                self._release_due(out)  # between batches: a burst never holds a due packet back

    def _on_packet(self, data: bytes, pos: int, end: int, now: int, real_minus_mono: int, out: list[bytes]) -> None:
        pid = None
        ifindex = 0
        stamp = 0
        cap_len = 0
        while pos + 4 <= end:
            alen, akind = struct.unpack_from("=HH", data, pos)
            if alen < 4:
                break
            akind &= 0x3FFF
            if akind == NFQA_PACKET_HDR:
                (pid,) = struct.unpack_from("!I", data, pos + 4)
            elif akind == NFQA_IFINDEX_PHYSOUTDEV:
                (ifindex,) = struct.unpack_from("!I", data, pos + 4)
            elif akind == NFQA_CAP_LEN:
                (cap_len,) = struct.unpack_from("!I", data, pos + 4)
            elif akind == NFQA_PAYLOAD and alen >= 8 and not cap_len:
                (cap_len,) = struct.unpack_from("!H", data, pos + 6)  # the IPv4 total length
            elif akind == NFQA_TIMESTAMP:
                sec, usec = struct.unpack_from("!QQ", data, pos + 4)
                stamp = sec * 1_000_000_000 + usec * 1000 - real_minus_mono
            pos += (alen + 3) & ~3
        if pid is None:
            return
        self.packets += 1
        base = now
        if stamp and stamp <= now + 1000 and now - stamp < 1_000_000_000:
            base = stamp
            self.kernel_ts += 1
            _bucket(self.recv_hist, (now - stamp) / 1000)
        delay = self.delay_ns.get(ifindex)
        if delay is None:
            self.unknown_port += 1
            delay = 0
        port = self.paced.get(ifindex)
        if port is not None:
            port.prune(now, self.lead_ns)
            start = port.admit(base + delay, (cap_len or 1500) + ETH_HLEN, pid)
            if start is None:
                out.append(verdict_msg(self.queue, pid, NF_DROP))
            else:
                heapq.heappush(self.heap, (start, pid))
        elif delay <= 0:
            out.append(verdict_msg(self.queue, pid))
        else:
            heapq.heappush(self.heap, (base + delay, pid))

    def _release_due(self, out: list[bytes]) -> None:
        now = time.monotonic_ns()
        heap = self.heap
        while heap and heap[0][0] <= now + self.lead_ns:
            due, pid = heapq.heappop(heap)
            out.append(verdict_msg(self.queue, pid))
            lag_us = max(0.0, (now - due) / 1000)
            self.max_lag_us = max(self.max_lag_us, lag_us)
            _bucket(self.lag_hist, lag_us)

    def _arm(self) -> None:
        spec = _Itimerspec()
        if self.heap:
            due = max(1, self.heap[0][0] - self.lead_ns)
            spec.it_value.tv_sec, spec.it_value.tv_nsec = divmod(due, 1_000_000_000)
        _libc.timerfd_settime(self.tfd, TFD_TIMER_ABSTIME, ctypes.byref(spec), None)

    def _flush(self, out: list[bytes]) -> None:
        if out:
            buf = b"".join(out)
            # one write per ~64 KB: the kernel walks every message in the buffer
            for i in range(0, len(buf), 60_000):
                chunk = buf[i:i + 60_000]
                # messages are fixed-size, so chunk boundaries fall on message boundaries
                try:
                    self.nl.send(chunk)
                except BlockingIOError:
                    select.select([], [self.nl], [], 0.01)
                    self.nl.send(chunk)
            out.clear()

    # control -----------------------------------------------------------------------------
    def _on_ctl(self) -> None:
        try:
            conn, _ = self.ctl.accept()
        except BlockingIOError:
            return
        with conn:
            try:
                conn.settimeout(0.2)  # a stuck client must not hold the verdict loop long
                raw = _recv_line(conn).decode(errors="replace")
                try:
                    reply = self._handle(raw)
                except ValueError as e:
                    reply = {"ok": False, "error": str(e)}
                conn.sendall(json.dumps(reply).encode() + b"\n")
            except OSError:  # the client went away: its loss, not the daemon's
                pass

    def _handle(self, line: str) -> dict:
        op, *items = line.split() or [""]
        if op == "set":
            delay_ns = dict(self.delay_ns)
            table = {}
            retimed = []
            for item in items:
                name, sep, value = item.partition("=")
                fields = value.split(",")
                try:
                    nums = [int(v) for v in fields]
                except ValueError:
                    nums = []
                if not sep or len(nums) not in (1, 4) or min(nums) < 0 or (len(nums) == 4 and nums[1] and not nums[2]):
                    raise ValueError(f"bad item {item}")
                try:
                    index = socket.if_nametoindex(name)
                except OSError:
                    raise ValueError(f"no interface {name}") from None
                table[name] = nums[0]
                delay_ns[index] = nums[0] * 1000
                if len(nums) == 4:
                    pacing = Pacing(*nums[1:])
                    port = self.paced.get(index)
                    if pacing.rate_bps == 0:
                        self.paced.pop(index, None)  # its queued frames keep their times
                    elif port is None:
                        self.paced[index] = PacedPort(pacing)
                        self.paced_names[name] = index
                    elif port.pacing != pacing:
                        port.pacing = pacing
                        retimed.append(port)
            self.delay_ns = delay_ns
            self.table_us.update(table)
            if retimed:
                self._rekey(retimed)
            return {"ok": True, "table": self.table_us, "pacing": self.pacing_table()}
        if op == "get":
            return {"ok": True, "table": self.table_us, "pacing": self.pacing_table(), "stats": self.stats()}
        if op == "stop":
            self.running = False
            return {"ok": True}
        return {"ok": False, "error": f"unknown op {op!r}"}

    def _rekey(self, ports: list[PacedPort]) -> None:
        now = time.monotonic_ns()
        start_of = {}
        for port in ports:
            port.prune(now, self.lead_ns)
            port.retime()
            start_of.update({f[4]: f[1] for f in port.frames})
        self.heap = [(start_of.get(pid, due), pid) for due, pid in self.heap]
        heapq.heapify(self.heap)

    def pacing_table(self) -> dict[str, list[int]]:
        return {name: self.paced[i].summary() for name, i in self.paced_names.items() if i in self.paced}

    def stats(self) -> dict:
        return {"impl": "python", "packets": self.packets, "queued": len(self.heap), "overflows": self.overflows,
                "unknown_port": self.unknown_port, "kernel_ts": self.kernel_ts,
                "max_lag_us": round(self.max_lag_us, 1), "lead_us": self.lead_ns / 1000,
                "lag_hist_us": dict(zip(map(str, LAG_BUCKETS_US), self.lag_hist)),
                "recv_hist_us": dict(zip(map(str, LAG_BUCKETS_US), self.recv_hist))}

    def serve(self) -> None:
        ep = select.epoll()
        ep.register(self.nl.fileno(), select.EPOLLIN)
        ep.register(self.tfd, select.EPOLLIN)
        ep.register(self.ctl.fileno(), select.EPOLLIN)
        out: list[bytes] = []
        while self.running:
            try:
                events = ep.poll(1.0)
            except InterruptedError:
                continue
            for fd, _ in events:
                if fd == self.nl.fileno():
                    self._on_packets(out)
                elif fd == self.tfd:
                    try:
                        os.read(self.tfd, 8)
                    except BlockingIOError:
                        pass
                elif fd == self.ctl.fileno():
                    self._on_ctl()
            self._release_due(out)
            self._flush(out)
            self._arm()


def _recv_line(sock: socket.socket) -> bytes:
    """One newline-terminated message of the control protocol (or what came before EOF)."""
    raw = b""
    while not raw.endswith(b"\n"):
        chunk = sock.recv(65536)
        if not chunk:
            break
        raw += chunk
    return raw


def request_line(req: dict) -> str:
    """The protocol line of a request dict ({"op": "set", "delays_us": {...}} / get / stop)."""
    op = req.get("op")
    if op == "set":
        pacing: dict[str, Pacing] = req.get("pacing") or {}
        unknown = sorted(set(pacing) - set(req["delays_us"]))
        if unknown:
            raise ValueError(f"pacing for ports without a delay: {unknown[:3]}")
        items = []
        for name, us in req["delays_us"].items():
            if not name or any(c.isspace() or c in "=," for c in name):
                raise ValueError(f"bad port name {name!r}")
            items.append(f"{name}={int(us)}" + (f",{pacing[name].item()}" if name in pacing else ""))
        return " ".join(["set", *items])
    if op in ("get", "stop"):
        return op
    raise ValueError(f"unknown op {op!r}")


def request(ctl_path: str, req: dict, timeout_s: float = 2.0) -> dict:
    """Send one control request to a running daemon and return its reply."""
    line = request_line(req).encode() + b"\n"
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(timeout_s)
        s.connect(ctl_path)
        s.sendall(line)
        raw = _recv_line(s)
    reply = json.loads(raw)
    if not reply.get("ok"):
        raise RuntimeError(f"delay daemon: {reply.get('error')}")
    return reply


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--queue", type=int, default=0)
    ap.add_argument("--ctl")
    ap.add_argument("--nice", type=int, default=-15)
    ap.add_argument("--rt", type=int, default=DELAY_RT_PRIORITY, help="SCHED_FIFO priority of the C helper (0: off)")
    ap.add_argument("--lead-us", type=float, default=DEFAULT_LEAD_US)
    ap.add_argument("--impl", choices=("auto", "c", "python"), default=os.environ.get(IMPL_ENV, "auto"),
                    help=f"auto: the C helper when it builds, else Python (default from ${IMPL_ENV})")
    ap.add_argument("--build", action="store_true", help="build the C helper, print its path and exit")
    args = ap.parse_args(argv)
    if args.build:
        path = build_helper(force=True)
        print(path if path else "no C compiler: the Python loop will be used")
        raise SystemExit(0 if path else 1)
    if not args.ctl:
        ap.error("--ctl is required")
    if args.impl != "python":
        helper = build_helper()
        if helper is not None:
            os.execv(helper, [str(helper), "--queue", str(args.queue), "--ctl", args.ctl, "--rt", str(args.rt),
                              "--nice", str(args.nice), "--lead-us", str(int(args.lead_us))])
        if args.impl == "c":
            raise SystemExit("nfqdelay: --impl c but the helper could not be built")
    _libc.prctl(PR_SET_TIMERSLACK, 1, 0, 0, 0)
    # The same real-time tier as the compiled loop: below it, the softirq threads and the
    # control plane (also SCHED_FIFO) took this loop's CPU and its median error went from 1 ms
    # to 13 ms (20-UAV DDoS). RT throttling keeps a whole core from being held for good.
    try:
        os.setpriority(os.PRIO_PROCESS, 0, args.nice)
        if args.rt > 0:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(args.rt))
    except OSError:
        pass
    gc.freeze()  # fewer, shorter collector pauses: they show up as delay outliers
    daemon = DelayDaemon(args.queue, args.ctl, lead_us=args.lead_us)

    def _stop(*_: object) -> None:
        raise SystemExit(0)  # breaks out of epoll at once (a flag would wait for the next wake-up)

    signal.signal(signal.SIGTERM, _stop)
    signal.signal(signal.SIGINT, _stop)
    print("ready", flush=True)
    try:
        daemon.serve()
    finally:
        try:
            os.unlink(args.ctl)
        except OSError:
            pass


if __name__ == "__main__":
    main()
