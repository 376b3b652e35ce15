"""Per-link, per-direction shaping of switch-to-switch ports: the `Shaper` interface.

Direction i -> j of a link is shaped on the *egress* of port `l<i>-<j>` (switch i's port towards
j), so a frame crossing k links meets k shaped egresses and accumulates each hop's delay and
loss, and both directions are independent. Backends, chosen by probing the kernel:

* `NetemShaper` (hosts with netem; Mininet TCLink style): HTB class for rate, netem child for
  delay and loss; each window `tc class change` + `tc qdisc change` (queues are kept).
* `FallbackShaper` (this kernel, no netem): the NFQUEUE delay daemon (`nfqdelay`) for delay,
  rate and queue: it paces each port through the audit's token-bucket FIFO from the frames'
  kernel stamps and drops the queue tail at the port's limit (`emulation.pacing`); for loss an
  nft bridge table, `oifname vmap @ports` -> one chain per port with a `numgen random` drop
  rule, rewritten atomically for changed ports only. Each port keeps the HTB class + `pfifo` it
  was created with (1 Gbit/s): it counts the frames sent and is never changed, so a window
  change is one request to the daemon, the nft batch and the fabric's, with no `tc` at all.
  Why the daemon paces and HTB does not: a backlogged HTB class refills only its one-frame
  bucket while the host is frozen (5-48 ms freezes were seen on this 2-core VM), so the rest of
  its busy period left late by the freeze; the daemon's schedule comes from the stamps.

Each backend reads back what the kernel/daemon actually hold; `records()` turns planned vs
applied into typed `ShapingRecord`s (one line of shaping.jsonl each). `counters()` reads each
port's kernel counters (packets sent by the rate stage, queue-tail drops, random-loss drops:
named nft counters, which survive the per-window rewrite of a port's rule); the runner reads
them at every window change and logs the deltas per window in shaping.jsonl.
"""

from __future__ import annotations

import json
import select
import subprocess
import sys
import time
from abc import ABC, abstractmethod
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from uavcas.network.queues import MTU_FRAME_B, netem_limit_pkts, queue_limit_pkts

from . import kernel, nfqdelay
from .counters import NFT_TABLE, PortCounters, read_link_drops, read_nft_counters, read_qdisc_counters
from .pacing import Pacing
from .readback import read_htb_classes, read_nft_losses

LOSS_SCALE = 1_000_000  # loss resolution: 1e-6
DEFAULT_RATE_MBPS = 1000.0
PACE_BURST_B = 1600  # the delay stage's bucket: one frame, the depth of tc's default HTB class (the link as before)


@dataclass(frozen=True)
class Shape:
    """Planned shaping of one direction of one link (src's switch -> dst's switch)."""

    src: str
    dst: str
    port: str  # egress port on src's switch
    rate_mbps: float
    delay_ms: float
    loss: float


@dataclass(frozen=True)
class Applied:
    rate_mbps: float | None
    delay_ms: float | None
    loss: float | None
    burst_b: int | None = None  # the bucket of the stage that paces the link (HTB's, or the delay stage's)


@dataclass(frozen=True)
class ShapingRecord:
    """One line of shaping.jsonl: planned vs applied for a link direction in a window."""

    window: int
    src: str
    dst: str
    port: str
    backend: str
    planned_rate_mbps: float
    planned_delay_ms: float
    planned_loss: float
    applied_rate_mbps: float | None
    applied_delay_ms: float | None
    applied_loss: float | None
    # kernel counters over the window (filled in at the window's end; None: not read)
    sent_packets: int | None = None
    queue_drops: int | None = None
    loss_drops: int | None = None
    link_drops: int | None = None
    paced_packets: int | None = None  # admitted by the delay stage's pacer (fallback backend only)
    # which setting of the window: 0 as the window was applied, k after its k-th mid-window
    # reshape (an attack's shaping, e.g. a jammer's start or stop); counters are per segment
    segment: int = 0
    # the bucket (bytes) of the stage that paces the link, read back from it: the audit's model
    # uses it. The HTB class's on the netem backend (tc's default is one 1600-byte "MTU" plus
    # rate/HZ where the kernel lacks high-resolution timers, so it is read back, not assumed);
    # the delay stage's on the fallback backend (None: not read back; runs made before it was
    # logged had 1600 B)
    applied_burst_b: int | None = None

    def to_dict(self) -> dict:
        return asdict(self)


def shaping_jsonl(records: Iterable[ShapingRecord]) -> str:
    """shaping.jsonl text (docs/formats.md): one JSON object per window and link direction."""
    return "".join(json.dumps(r.to_dict(), sort_keys=True) + "\n" for r in records)


def rate_bit(rate_mbps: float) -> int:
    return max(8, round(rate_mbps * 1e6))


def htb_init_lines(port: str, rate_mbps: float = DEFAULT_RATE_MBPS) -> list[str]:
    r = rate_bit(rate_mbps)
    return [f"qdisc add dev {port} root handle 1: htb default 1",
            f"class add dev {port} parent 1: classid 1:1 htb rate {r}bit ceil {r}bit quantum {MTU_FRAME_B}"]


def htb_change_line(port: str, rate_mbps: float) -> str:
    r = rate_bit(rate_mbps)
    return f"class change dev {port} parent 1: classid 1:1 htb rate {r}bit ceil {r}bit quantum {MTU_FRAME_B}"


def pacing(rate_mbps: float) -> Pacing:
    """The delay stage's pacing of a port at `rate_mbps`: one-frame bucket, the port's queue limit."""
    return Pacing(rate_bit(rate_mbps), PACE_BURST_B, queue_limit_pkts(rate_mbps))


def pfifo_line(verb: str, port: str, rate_mbps: float) -> str:
    return f"qdisc {verb} dev {port} parent 1:1 handle 10: pfifo limit {queue_limit_pkts(rate_mbps)}"


def netem_line(verb: str, port: str, delay_ms: float, loss: float, rate_mbps: float) -> str:
    delay_us = round(delay_ms * 1000)
    loss_pct = f"{loss * 100:.4f}".rstrip("0").rstrip(".")
    return (f"qdisc {verb} dev {port} parent 1:1 handle 10: netem delay {delay_us}us loss {loss_pct}% "
            f"limit {netem_limit_pkts(rate_mbps, delay_ms)}")


def nft_chain(port: str) -> str:
    return "p_" + port.replace("-", "_")


def nft_table_ruleset(table: str = NFT_TABLE) -> str:
    """The loss table: one rule `oifname vmap @ports` jumping to a chain per link port.

    Each port's chain holds at most one rule, `numgen random mod 10^6 < p*10^6 drop`. A window
    rewrites only the chains whose loss changed (flush + add, one atomic `nft -f`): ~10 ms for
    300 ports here, where rebuilding the whole table took 25-40 ms and an interval map keyed by
    (port . random draw) took 60+ ms per update (its pipapo set is re-cloned on every commit).
    """
    return (f"table bridge {table} {{\n"
            f"  map ports {{\n    type ifname : verdict\n  }}\n"
            f"  chain linkloss {{\n    type filter hook forward priority -10; policy accept;\n"
            f"    oifname vmap @ports\n  }}\n}}\n")


def nft_counter(port: str) -> str:
    return "c_" + port.replace("-", "_")


def nft_port_init_lines(ports: Sequence[str], table: str = NFT_TABLE) -> list[str]:
    lines = [f"add chain bridge {table} {nft_chain(p)}" for p in ports]
    lines += [f"add counter bridge {table} {nft_counter(p)}" for p in ports]
    if ports:
        elems = ", ".join(f'"{p}" : jump {nft_chain(p)}' for p in ports)
        lines.append(f"add element bridge {table} ports {{ {elems} }}")
    return lines


def nft_loss_lines(loss_by_port: dict[str, float], table: str = NFT_TABLE) -> list[str]:
    lines = []
    for port, loss in sorted(loss_by_port.items()):
        thr = min(LOSS_SCALE, round(loss * LOSS_SCALE))
        lines.append(f"flush chain bridge {table} {nft_chain(port)}")
        if thr >= LOSS_SCALE:  # `numgen mod N < N` is refused by nft; a dead link drops everything
            lines.append(f"add rule bridge {table} {nft_chain(port)} counter name {nft_counter(port)} drop")
        elif thr > 0:
            lines.append(f"add rule bridge {table} {nft_chain(port)} numgen random mod {LOSS_SCALE} < {thr} "
                         f"counter name {nft_counter(port)} drop")
    return lines


class Shaper(ABC):
    backend = "abstract"

    def __init__(self, fabric_ns: str, run_dir: Path) -> None:
        self.fabric_ns = fabric_ns
        self.run_dir = run_dir
        self.current: dict[str, Shape] = {}  # port -> last applied plan

    def start(self) -> None:
        """Called once the fabric namespace exists, before any port (rules, tables, daemons)."""

    def wait_ready(self) -> None:
        """Block until helpers started by `start` serve (lets their start-up overlap the setup)."""

    def stop(self) -> None:
        """Stop helpers; the namespace's deletion removes qdiscs and rules."""

    def check(self) -> None:
        """Raise KernelError if a helper the shaping depends on is gone (called every window)."""

    @abstractmethod
    def init_lines(self, ports: Sequence[str]) -> list[str]:
        """tc batch lines preparing freshly created (still down) ports."""

    def init_batches(self, ports: Sequence[str]) -> list[kernel.Batch]:
        """Every batch preparing freshly created ports (run concurrently with other setup)."""
        return [kernel.Batch("tc", self.fabric_ns, self.init_lines(ports))]

    @abstractmethod
    def apply(self, shapes: Sequence[Shape], also: Sequence[kernel.Batch] = ()) -> dict[str, float]:
        """Change parameters in place for ports whose plan changed; returns stage timings (s).

        `also`: independent batches (e.g. links going down) run concurrently with the shaping.
        """

    @abstractmethod
    def readback(self, ports: Sequence[str]) -> dict[str, Applied]:
        """What the kernel (and daemon) hold now for these ports."""

    def counters(self, ports: Sequence[str]) -> dict[str, PortCounters]:
        """Cumulative kernel counters per port (empty where the backend cannot read them)."""
        return {}

    def records(self, window: int, shapes: Sequence[Shape], applied: dict[str, Applied]) -> list[ShapingRecord]:
        out = []
        for s in shapes:
            a = applied.get(s.port, Applied(None, None, None))
            out.append(ShapingRecord(window, s.src, s.dst, s.port, self.backend, s.rate_mbps, s.delay_ms, s.loss,
                                     a.rate_mbps, a.delay_ms, a.loss, applied_burst_b=a.burst_b))
        return out

    def _changed(self, shapes: Iterable[Shape]) -> list[Shape]:
        return [s for s in shapes if self.current.get(s.port) != s]


class NetemShaper(Shaper):
    """HTB (rate) with a netem child (delay, loss) per port; everything changed in place."""

    backend = "netem"

    def init_lines(self, ports: Sequence[str]) -> list[str]:
        lines = []
        for p in ports:
            lines += htb_init_lines(p)
            lines.append(netem_line("add", p, 0.0, 0.0, DEFAULT_RATE_MBPS))
        return lines

    def change_lines(self, shapes: Sequence[Shape]) -> list[str]:
        lines = []
        for s in self._changed(shapes):
            old = self.current.get(s.port)
            if old is None or old.rate_mbps != s.rate_mbps:
                lines.append(htb_change_line(s.port, s.rate_mbps))
            lines.append(netem_line("change", s.port, s.delay_ms, s.loss, s.rate_mbps))
        return lines

    def apply(self, shapes: Sequence[Shape], also: Sequence[kernel.Batch] = ()) -> dict[str, float]:
        t0 = time.perf_counter()
        kernel.run_batches([kernel.Batch("tc", self.fabric_ns, self.change_lines(shapes)), *also])
        self.current.update({s.port: s for s in shapes})
        return {"kernel_s": time.perf_counter() - t0}

    def readback(self, ports: Sequence[str]) -> dict[str, Applied]:
        htb = read_htb_classes(self.fabric_ns, ports)
        qd = json.loads(kernel.run(["tc", "-n", self.fabric_ns, "-j", "qdisc", "show"]).stdout or "[]")
        netem = {q.get("dev"): q.get("options", {}) for q in qd if q.get("kind") == "netem"}
        out = {}
        for p in ports:
            opt = netem.get(p, {})
            delay = opt.get("delay", {})
            delay_s = delay.get("delay") if isinstance(delay, dict) else None
            loss = opt.get("loss-random", {}).get("loss", 0.0) if netem.get(p) is not None else None
            rate, burst = htb.get(p, (None, None))
            out[p] = Applied(rate, None if delay_s is None else delay_s * 1000, loss, burst)
        return out

    def counters(self, ports: Sequence[str]) -> dict[str, PortCounters]:
        # netem drops random losses and a full queue alike: one count, reported as loss drops
        qd, link = read_qdisc_counters(self.fabric_ns), read_link_drops(self.fabric_ns)
        return {p: PortCounters(qd[p]["htb"].get("packets"), None, qd[p].get("netem", {}).get("drops"), link.get(p))
                for p in ports if "htb" in qd.get(p, {})}


class FallbackShaper(Shaper):
    """No netem: NFQUEUE daemon (delay, rate, queue), nft numgen (loss); HTB + pfifo only count."""

    backend = "htb-nft-nfqueue"
    queue_num = 0

    def __init__(self, fabric_ns: str, run_dir: Path) -> None:
        super().__init__(fabric_ns, run_dir)
        self.daemon: subprocess.Popen | None = None
        self.ctl_path = str(run_dir / "delay.sock")

    def start(self) -> None:
        kernel.run(["ip", "netns", "exec", self.fabric_ns, "iptables", "-w", "-A", "FORWARD", "-m", "physdev",
                    "--physdev-out", "l+", "-j", "NFQUEUE", "--queue-num", str(self.queue_num), "--queue-bypass"])
        kernel.run(["ip", "netns", "exec", self.fabric_ns, "nft", "-f", "-"], input_text=nft_table_ruleset())
        log = open(self.run_dir / "nfqdelay.log", "ab")
        # `ip netns exec` execs, so Popen.pid is the daemon itself (killable by PID, listed by
        # `ip netns pids` for `uavcas clean`). Its own session: a Ctrl-C to the terminal's
        # process group reaches only the runner, which stops the daemon last, after the tools.
        self.daemon = subprocess.Popen(
            ["ip", "netns", "exec", self.fabric_ns, sys.executable, "-m", "uavcas.emulation.nfqdelay",
             "--queue", str(self.queue_num), "--ctl", self.ctl_path],
            stdout=subprocess.PIPE, stderr=log, stdin=subprocess.DEVNULL, start_new_session=True)
        log.close()

    def check(self) -> None:
        """The daemon must live as long as the run: without it packets pass undelayed
        (`--queue-bypass`), so a run that lost it fails here instead of recording wrong delays."""
        if self.daemon is not None and self.daemon.poll() is not None:
            rc = self.daemon.returncode
            how = f"killed by signal {-rc}" if rc < 0 else f"exit status {rc}"
            err = (self.run_dir / "nfqdelay.log").read_text(errors="replace").strip().splitlines()
            raise kernel.KernelError(f"NFQUEUE delay daemon died ({how}){': ' + err[-1] if err else ''}")

    def wait_ready(self) -> None:
        ready, _, _ = select.select([self.daemon.stdout], [], [], 10.0)
        line = self.daemon.stdout.readline() if ready else b""
        if line.strip() != b"ready":
            self.stop()
            err = (self.run_dir / "nfqdelay.log").read_text(errors="replace")[-500:]
            raise kernel.KernelError(f"NFQUEUE delay daemon did not start: {err.strip()}")

    def stop(self) -> None:
        if self.daemon is not None and self.daemon.poll() is None:
            self.daemon.terminate()
            try:
                self.daemon.wait(1.0)
            except subprocess.TimeoutExpired:
                self.daemon.kill()
                self.daemon.wait(2.0)
        self.daemon = None

    def init_lines(self, ports: Sequence[str]) -> list[str]:
        lines = []
        for p in ports:
            lines += htb_init_lines(p)
            lines.append(pfifo_line("add", p, DEFAULT_RATE_MBPS))
        return lines

    def init_batches(self, ports: Sequence[str]) -> list[kernel.Batch]:
        return [kernel.Batch("tc", self.fabric_ns, self.init_lines(ports)),
                kernel.Batch("nft", self.fabric_ns, nft_port_init_lines(ports))]

    def daemon_request(self, shapes: Sequence[Shape]) -> dict | None:
        """Every changed port's delay and pacing, in one request (None: nothing changed); the
        daemon re-times a port's queued frames when its rate changes."""
        return _set_request(self._changed(shapes))

    def apply(self, shapes: Sequence[Shape], also: Sequence[kernel.Batch] = ()) -> dict[str, float]:
        changed = self._changed(shapes)
        new = {**self.current, **{s.port: s for s in shapes}}
        batches = list(also)
        losses = {s.port: s.loss for s in changed if (self.current.get(s.port) or _NOLOSS).loss != s.loss}
        if losses:
            batches.append(kernel.Batch("nft", self.fabric_ns, nft_loss_lines(losses)))
        request = _set_request(changed)
        t1 = time.perf_counter()
        if request:  # a socket round trip to the daemon (~1 ms); nft and ip run concurrently
            nfqdelay.request(self.ctl_path, request)
        t2 = time.perf_counter()
        kernel.run_batches(batches)
        self.current = new
        return {"delay_s": t2 - t1, "kernel_s": time.perf_counter() - t2}

    def readback(self, ports: Sequence[str]) -> dict[str, Applied]:
        htb = read_htb_classes(self.fabric_ns, ports)
        losses = read_nft_losses(self.fabric_ns)
        got = nfqdelay.request(self.ctl_path, {"op": "get"}) if self.daemon else {}
        table, paced = got.get("table", {}), got.get("pacing", {})
        out = {}
        for p in ports:
            # the pacing daemon's rate and bucket, which shape the link; HTB's where it paces none
            rate, burst = (paced[p][0] / 1e6, paced[p][1]) if p in paced else htb.get(p, (None, None))
            out[p] = Applied(rate, table[p] / 1000 if p in table else None, losses.get(p, 0.0), burst)
        return out

    def counters(self, ports: Sequence[str]) -> dict[str, PortCounters]:
        qd, link = read_qdisc_counters(self.fabric_ns), read_link_drops(self.fabric_ns)
        nft = read_nft_counters(self.fabric_ns)
        paced = nfqdelay.request(self.ctl_path, {"op": "get"}).get("pacing", {}) if self.daemon else {}

        def tail_drops(p: str) -> int | None:  # the daemon's at its queue limit, and the pfifo's (none)
            pf = qd[p].get("pfifo", {}).get("drops")
            return None if pf is None and p not in paced else (pf or 0) + (paced[p][4] if p in paced else 0)
        return {p: PortCounters(qd[p]["htb"].get("packets"), tail_drops(p), nft.get(p, 0), link.get(p),
                                paced[p][3] if p in paced else None)
                for p in ports if "htb" in qd.get(p, {})}

    def daemon_stats(self) -> dict:
        return nfqdelay.request(self.ctl_path, {"op": "get"})["stats"]


_NOLOSS = Shape("", "", "", DEFAULT_RATE_MBPS, 0.0, 0.0)


def _set_request(changed: Sequence[Shape]) -> dict | None:
    """The daemon's `set` request for the changed shapes (None: none)."""
    if not changed:
        return None
    return {"op": "set", "delays_us": {s.port: round(s.delay_ms * 1000) for s in changed},
            "pacing": {s.port: pacing(s.rate_mbps) for s in changed}}


def make_shaper(backend: str, fabric_ns: str, run_dir: Path) -> Shaper:
    if backend == "netem":
        return NetemShaper(fabric_ns, run_dir)
    if backend == "htb-nft-nfqueue":
        return FallbackShaper(fabric_ns, run_dir)
    raise ValueError(f"no usable shaper on this kernel (backend {backend!r}); run `uavcas doctor`")
