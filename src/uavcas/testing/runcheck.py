"""Reading a run directory back (dpkt): what the pcaps hold vs what attacks.jsonl says; and
finding a run in the registry.

Used by the root tests and the benchmarks; independent of uavcas.flows on purpose (a second
opinion on the captures). Needs dpkt (the `test` or `bench` extra).
"""

from __future__ import annotations

import json
import socket
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import dpkt

from uavcas.rundir import RunDir


@dataclass
class Pkt:
    t: float
    src: str
    dst: str
    proto: int
    sport: int
    dport: int
    flags: int
    ttl: int
    ip_id: int
    seq: int | None
    size: int


def read_pcap(path: Path) -> list[Pkt]:
    out = []
    with open(path, "rb") as fh:
        for ts, buf in dpkt.pcap.Reader(fh):
            eth = dpkt.ethernet.Ethernet(buf)
            ip = eth.data
            if not isinstance(ip, dpkt.ip.IP):
                continue
            l4 = ip.data
            sport = dport = flags = 0
            seq = None
            if isinstance(l4, dpkt.tcp.TCP):
                sport, dport, flags, seq = l4.sport, l4.dport, l4.flags, l4.seq
            elif isinstance(l4, dpkt.udp.UDP):
                sport, dport = l4.sport, l4.dport
            out.append(Pkt(float(ts), socket.inet_ntoa(ip.src), socket.inet_ntoa(ip.dst), ip.p, sport, dport, flags,
                           ip.ttl, ip.id, seq, len(buf)))
    return out


def attack_log(run: Path) -> list[dict]:
    return [json.loads(x) for x in (run / "attacks.jsonl").read_text().splitlines() if x.strip()]


def windows(run: Path) -> dict[str, tuple[float, float, dict]]:
    """attack_id -> (start, stop, start record)."""
    recs = attack_log(run)
    starts = {r["attack_id"]: r for r in recs if r["event"] == "start"}
    stops = {r["attack_id"]: r["t_unix"] for r in recs if r["event"] == "stop"}
    return {k: (v["t_unix"], stops.get(k, float("inf")), v) for k, v in starts.items()}


def crossed(run: Path) -> dict[str, float]:
    """attack_id -> the end of the span holding every observation of its packets: the stop's
    `crossed_unix` (floods, mavlink_inject: their stop is when the last packet left), else the stop."""
    stops = [r for r in attack_log(run) if r["event"] == "stop"]
    return {r["attack_id"]: r.get("crossed_unix") or r["t_unix"] for r in stops}


def is_syn(p: Pkt) -> bool:
    return p.proto == 6 and (p.flags & dpkt.tcp.TH_SYN) and not (p.flags & dpkt.tcp.TH_ACK)


@dataclass
class FloodCheck:
    inside: int
    outside: int
    seconds: float
    per_second: list[int] = field(default_factory=list)

    @property
    def pps(self) -> float:
        return self.inside / self.seconds if self.seconds else 0.0


def flood_check(pkts: list[Pkt], attacker_ip: str, victim_ip: str, start: float, stop: float,
                port: int = 80, until: float | None = None) -> FloodCheck:
    """SYNs inside the sending window [start, stop) (their rate) and outside [start, until) (by
    default `until` = stop; a flood's `crossed` when its SYNs may still cross after the stop)."""
    syns = [p.t for p in pkts if is_syn(p) and p.src == attacker_ip and p.dst == victim_ip and p.dport == port]
    inside = [t for t in syns if start <= t < stop]
    end = stop if until is None else max(stop, until)
    per_s = Counter(int(t - start) for t in inside)
    return FloodCheck(len(inside), sum(not start <= t < end for t in syns), stop - start,
                      [per_s[k] for k in range(int(stop - start) + 1)])


def http_transfers(pkts: list[Pkt], server_ip: str) -> tuple[int, int]:
    """(connections opened to server:80, payload-carrying packets from server:80)."""
    conns = {(p.src, p.sport) for p in pkts if is_syn(p) and p.dst == server_ip and p.dport == 80}
    data = sum(1 for p in pkts if p.src == server_ip and p.sport == 80 and p.size > 200)
    return len(conns), data


def hop_delays(run: Path, max_dt_s: float = 0.1, max_size: int = 100_000) -> dict[tuple[str, str], list[float]]:
    """Measured one-way delay per link direction a -> b, from the captures themselves.

    A frame crossing link a -> b is captured entering switch a, then entering switch b; the
    difference of the two capture times is that hop's delay as the wire saw it (propagation
    delay of the shaper + serialisation + queueing + a bridge traversal). Frames are matched by
    (src, dst, proto, ports, IP id, seq); only links active in the frame's window count.
    `max_size` keeps small frames only (SYNs, ACKs), whose serialisation time is negligible.
    """
    plan = json.loads((run / "plan.json").read_text())
    ip_of = {n["name"]: n["ip"] for n in plan["nodes"]}
    t0 = json.loads((run / "run.json").read_text())["t0_unix"]
    ws = plan["window_s"]
    active = [{(lk["a"], lk["b"]) for lk in w["links"]} | {(lk["b"], lk["a"]) for lk in w["links"]}
              for w in plan["windows"]]
    first: dict[str, dict[tuple, float]] = {}
    for node in ip_of:
        seen: dict[tuple, float] = {}
        for p in read_pcap(run / "pcap" / f"s-{node}.pcap"):
            if p.size <= max_size:
                seen.setdefault((p.src, p.dst, p.proto, p.sport, p.dport, p.ip_id, p.seq), p.t)
        first[node] = seen
    out: dict[tuple[str, str], list[float]] = {}
    pairs = set().union(*active) if active else set()
    for a, b in pairs:
        sa, sb = first[a], first[b]
        dts = []
        for k, ta in sa.items():
            tb = sb.get(k)
            if tb is None or not 0 < tb - ta < max_dt_s:
                continue
            w = min(len(active) - 1, max(0, int((ta - t0) // ws)))
            if (a, b) in active[w]:
                dts.append(tb - ta)
        out[(a, b)] = dts
    return out


def wait_registered(pid: int, since_unix: float, timeout_s: float = 60.0) -> str:
    """The prefix under which the run with this PID registered itself in /run/uavcas.

    PIDs wrap (pid_max is 32768 here) and a crashed run's registry entry outlives its process,
    so an entry only counts if it was written after our process started."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        for p in Path("/run/uavcas").glob("uc*"):
            try:
                rec = json.loads((p / "run.json").read_text())
            except (FileNotFoundError, ValueError):
                continue
            if rec["pid"] == pid and rec["created_unix"] >= since_unix:
                return p.name
        time.sleep(0.1)
    raise AssertionError("the run never registered")


def wait_started(out_dir: Path, timeout_s: float = 120.0) -> float:
    """Wait until the run writing `out_dir` reached its plan's t = 0; returns that wall-clock time.

    Set-up (namespaces, the delay stage, MAVLink endpoints) takes from 2 s idle to over 10 s on a
    loaded 2-core box, so a test that must interrupt a run *after* traffic started waits for this,
    not for a fixed sleep."""
    rd = RunDir(out_dir)
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        owner = rd.read_owner()  # written atomically: absent or whole
        if owner is not None and owner.t0_unix is not None:
            return owner.t0_unix
        time.sleep(0.1)
    raise AssertionError(f"{out_dir}: the run never reached t = 0")
