"""Flow termination policies: where the packets of one key are cut into flows.

Three named policies (`FlowConfig.termination`; the dataset card records the one in force):

`connection` (default for the 5-tuple view): one TCP connection is one flow.
- A flow closes on RST, or when both directions have sent FIN and the LAST FIN is acknowledged
  (an ACK from the other side whose acknowledgement number reaches past that FIN; serial
  arithmetic, RFC 1982, so sequence wrap-around is handled).
- After the close, packets of the key that arrive within the grace period (`CLOSE_GRACE_S`,
  measured from the closing packet) join the closed flow: trailing ACKs, a retransmitted FIN,
  SYN-ACK or RST. These are the "TCP appendices" a first-FIN cut splits off into flows of their
  own (Engelen, Rimmer, Joosen, "Troubleshooting an Intrusion Detection Dataset: the CICIDS2017
  Case Study", WTMC 2021). A new SYN without ACK after the close starts a new flow (port reuse),
  and so does any packet after the grace period.
- While open: the idle timeout (a gap since the flow's previous packet) and the active timeout
  (since its first packet) start a new flow. Before the handshake completes (no packet with ACK
  and without SYN yet), so does a SYN without ACK that does not repeat the flow's opening SYN
  (same sender and sequence number): hping3 floods and restarted clients reuse 5-tuples. Once
  established, a SYN belongs to the connection (its stack answers it with a challenge ACK, RFC
  5961): a SYN injected into a live connection stays in that connection's flow. Within the grace
  period the idle timeout does not apply: a closed connection is silent by design, and what still
  comes (retransmissions) comes after exponential back-off.
- Non-TCP keys: the timeouts only.
- Grace period: 60 s, Linux's TIME_WAIT (`TCP_TIMEWAIT_LEN`), the time the closing host itself
  keeps the 5-tuple bound to the old connection and treats its segments as that connection's
  (RFC 9293 sec. 3.6.1: 2 MSL). It covers FIN retransmissions and the SYN-ACK retransmissions that
  a lost RST provokes (Linux sends them 1, 3, 7, 15 and 31 s after the SYN with the default
  tcp_synack_retries = 5), and it is longer than the twin's runs' gaps between separate
  connections of one 5-tuple, which are new SYNs anyway.

`cic`: CICFlowMeter's FlowGenerator.addPacket (CICFlowMeter-4.0, github.com/ahlashkari/CICFlowMeter,
`FlowGenerator.java`) exactly, the appendix artifact included:
- a packet more than the flow timeout (120 s, `>`) after the flow's first packet ends the flow and
  starts the next one, which keeps the old flow's orientation but counts its own first packet as
  forward (`new BasicFlow(..., flow.getSrc(), ...)` after `firstPacket`);
- else a FIN: a backward FIN is added and closes the flow at once (the code tests
  `getBwdFINFlags() + getBwdFINFlags() == 2`, so the first backward FIN closes); the first forward
  FIN is added and closes nothing; a second forward FIN is dropped (belongs to no flow);
- else a RST is added and closes the flow; else the packet is added;
- a packet after a close starts a new flow (no grace), whatever its flags;
- orientation: the first packet's sender is forward (no SYN-ACK rule);
- flows of one packet are never written (`packetCount() > 1`): the policy's minimum size is 2.
- no idle timeout and no SYN rule.
Known difference: CICFlowMeter compares only source addresses for the direction; here the
endpoint (address and port) is compared, which differs only for a host talking to itself.

`timeout` (nfstream's): the idle and active timeouts only (nfstream's defaults: 120 s idle,
1800 s active).

Every rule looks only at earlier packets of the key, so a capture read in blocks gives the same
flows as one read whole (`uavcas.flows.stream`), with one exception documented there (a `cic`
flow continued after the flow timeout whose predecessor was already released).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

Termination = Literal["connection", "cic", "timeout"]
TERMINATIONS: tuple[str, ...] = ("connection", "cic", "timeout")
TCP_FIN, TCP_SYN, TCP_RST, TCP_ACK = 0x01, 0x02, 0x04, 0x10
NS = 1_000_000_000
CLOSE_GRACE_S = 60.0  # Linux TCP_TIMEWAIT_LEN (see the module docstring)
_HALF = 1 << 31
_MOD = 1 << 32


@dataclass(frozen=True)
class PolicyDefaults:
    """A policy's defaults where the user sets nothing."""

    idle_timeout_s: float | None
    active_timeout_s: float | None
    min_packets: int
    grace_s: float


DEFAULTS: dict[str, PolicyDefaults] = {
    # Cisco NetFlow's inactive timeout (15 s) and CICFlowMeter's flow timeout (120 s)
    "connection": PolicyDefaults(15.0, 120.0, 1, CLOSE_GRACE_S),
    "cic": PolicyDefaults(None, 120.0, 2, 0.0),
    "timeout": PolicyDefaults(120.0, 1800.0, 1, 0.0),  # nfstream's idle_timeout / active_timeout
}


@dataclass(frozen=True)
class KeyPackets:
    """The packets of a run in key order (one key's packets contiguous, each key's by time)."""

    ts: np.ndarray  # int64 ns
    is_a: np.ndarray  # bool: sent by the key's 'a' endpoint
    flags: np.ndarray
    proto: np.ndarray
    seq: np.ndarray
    ack: np.ndarray
    payload: np.ndarray  # transport payload bytes (`flows.packets.payload_and_header`)
    key_starts: np.ndarray  # offsets of each key's first packet, closed by n


@dataclass(frozen=True)
class Cuts:
    """Where flows start (`starts`, closed by n), which packets belong to a flow (`keep`: False for a
    packet CICFlowMeter drops), the forward direction of every packet (`fwd`) and, per flow, when it
    closed (`close_ns`, -1 while open) and whether its forward endpoint is its first packet's
    DESTINATION although that packet counts forward (`turned`: a `cic` flow continued after the
    flow timeout whose first packet came from the old flow's destination; None: never)."""

    starts: np.ndarray
    keep: np.ndarray
    fwd: np.ndarray
    close_ns: np.ndarray
    turned: np.ndarray | None = None


def synack_turned(is_a: np.ndarray, flags: np.ndarray, proto: np.ndarray) -> np.ndarray:
    """Forward = 'a' sends forward? The first packet's sender, except that a TCP flow whose first
    packet is a SYN-ACK (the SYN was missed) is turned around so the SYN sender is forward."""
    synack = (proto == 6) & ((flags & (TCP_SYN | TCP_ACK)) == (TCP_SYN | TCP_ACK))
    return np.where(synack, ~is_a, is_a)


def timeout_starts(ts: np.ndarray, key_starts: np.ndarray, idle_ns: int | None, active_ns: int | None) -> np.ndarray:
    """Flow starts (closed by n) from the key boundaries and the two timeouts alone."""
    n = ts.shape[0]
    new = np.zeros(n, dtype=bool)
    new[key_starts[:-1]] = True
    if idle_ns is not None and n > 1:
        new[1:] |= np.diff(ts) >= idle_ns
    starts = np.append(np.flatnonzero(new), n).astype(np.int64)
    if active_ns is None:
        return starts
    # the active timeout depends on the current flow's first packet: cut, then look again
    cuts = [starts]
    todo_s, todo_e = starts[:-1], starts[1:]
    sel = (todo_e - todo_s > 1) & (ts[todo_e - 1] - ts[todo_s] > active_ns)
    todo_s, todo_e = todo_s[sel], todo_e[sel]
    while todo_s.shape[0]:
        length = todo_e - todo_s
        seg = np.repeat(np.arange(todo_s.shape[0]), length)
        pos = np.arange(length.sum()) - np.repeat(np.cumsum(length) - length, length) + np.repeat(todo_s, length)
        late = np.where(ts[pos] - ts[todo_s[seg]] > active_ns, pos, n + 1)
        best = np.minimum.reduceat(late, np.cumsum(length) - length)
        ok = best < todo_e
        cuts.append(best[ok])
        todo_s, todo_e = best[ok], todo_e[ok]
        keep = todo_e - todo_s > 1
        todo_s, todo_e = todo_s[keep], todo_e[keep]
    return np.unique(np.concatenate(cuts))


def _reaches(ack: int, end: int) -> bool:
    """ack >= end in 32-bit serial arithmetic."""
    return (ack - end) % _MOD < _HALF


class _Connection:
    """The connection policy's state for the current flow of one TCP key."""

    __slots__ = ("first", "closed_at", "fin_end", "fin_acked", "last_fin", "established")

    def __init__(self, first: int) -> None:
        self.first, self.closed_at, self.last_fin = first, -1, -1
        self.established = False  # a packet with ACK and without SYN was seen: past the handshake
        self.fin_end: list[int | None] = [None, None]  # per direction (0: b, 1: a): the sequence after its FIN
        self.fin_acked = [False, False]

    def add(self, k: int, t: int, d: int, f: int, seq: int, ack: int, payload: int) -> None:
        """Packet k (time t, direction d, flags f) joins the open flow: RST closes it; FINs and the
        ACKs of FINs close it once both sides sent FIN and the last FIN is acknowledged. The flow's
        first packet counts too (an orphan RST closes its one-packet flow)."""
        if f & TCP_RST:
            self.closed_at = t
            return
        if f & TCP_ACK and not f & TCP_SYN:
            self.established = True
        other = self.fin_end[1 - d]
        if f & TCP_ACK and other is not None and _reaches(ack, other):
            self.fin_acked[1 - d] = True
        if f & TCP_FIN:
            end = (seq + payload + 1 + (1 if f & TCP_SYN else 0)) % _MOD
            if self.fin_end[d] is None or _reaches(end, self.fin_end[d]):
                self.fin_end[d] = end
            self.last_fin = d
        if self.fin_end[0] is not None and self.fin_end[1] is not None and self.fin_acked[self.last_fin]:
            self.closed_at = t


def _connection_key(ts, is_a, flags, seq, ack, payload, lo, hi, idle_ns, active_ns, grace_ns, starts, close):
    """The connection policy over one TCP key's packets [lo, hi): appends flow starts and closes."""
    c = _Connection(lo)
    starts.append(lo)
    c.add(lo, ts[lo], is_a[lo], flags[lo], seq[lo], ack[lo], payload[lo])
    for k in range(lo + 1, hi):
        f = flags[k]
        pure_syn = (f & (TCP_SYN | TCP_ACK)) == TCP_SYN
        if c.closed_at >= 0:
            if not pure_syn and ts[k] - c.closed_at <= grace_ns:
                continue  # an appendix of the closed connection joins it
            new = True
        else:
            first = c.first
            again = pure_syn and is_a[k] == is_a[first] and seq[k] == seq[first] \
                and (flags[first] & (TCP_SYN | TCP_ACK)) == TCP_SYN
            new = ((idle_ns is not None and ts[k] - ts[k - 1] >= idle_ns)
                   or (active_ns is not None and ts[k] - ts[first] > active_ns)
                   or (pure_syn and not again and not c.established))
        if new:
            close.append(c.closed_at)
            starts.append(k)
            c = _Connection(k)
        c.add(k, ts[k], is_a[k], f, seq[k], ack[k], payload[k])
    close.append(c.closed_at)


def connection_cuts(kp: KeyPackets, idle_ns: int | None, active_ns: int | None, grace_ns: int) -> Cuts:
    """The `connection` policy (module docstring)."""
    n = kp.ts.shape[0]
    seg_len = np.diff(kp.key_starts)
    key_tcp = kp.proto[kp.key_starts[:-1]] == 6 if n else np.zeros(0, dtype=bool)
    loop = key_tcp & (seg_len > 1)
    # keys the state machine does not need: the timeouts alone, vectorised
    simple = timeout_starts(kp.ts, kp.key_starts, idle_ns, active_ns)
    in_loop = np.repeat(loop, seg_len)
    starts_l: list[int] = []
    close_l: list[int] = []
    if loop.any():
        ts, is_a, flags = kp.ts.tolist(), kp.is_a.tolist(), kp.flags.tolist()
        seq, ack, payload = kp.seq.tolist(), kp.ack.tolist(), kp.payload.tolist()
        for lo, hi in zip(kp.key_starts[:-1][loop].tolist(), kp.key_starts[1:][loop].tolist()):
            _connection_key(ts, is_a, flags, seq, ack, payload, lo, hi, idle_ns, active_ns, grace_ns, starts_l, close_l)
    s_simple = simple[:-1][~in_loop[simple[:-1]]] if n else np.zeros(0, dtype=np.int64)
    starts = np.concatenate([s_simple, np.asarray(starts_l, dtype=np.int64)])
    close = np.concatenate([np.full(s_simple.shape[0], -1, dtype=np.int64), np.asarray(close_l, dtype=np.int64)])
    o = np.argsort(starts, kind="stable")
    return _initiator_cuts(kp, np.append(starts[o], n).astype(np.int64), close[o])


def _initiator_cuts(kp: KeyPackets, starts: np.ndarray, close: np.ndarray) -> Cuts:
    """Cuts that keep every packet, each flow oriented to its initiator (`synack_turned`)."""
    flow = np.repeat(np.arange(starts.shape[0] - 1), np.diff(starts))
    f0 = starts[:-1]
    fwd_a = synack_turned(kp.is_a[f0], kp.flags[f0], kp.proto[f0])
    return Cuts(starts, np.ones(kp.ts.shape[0], dtype=bool), kp.is_a == fwd_a[flow], close)


def cic_cuts(kp: KeyPackets, idle_ns: int | None, active_ns: int | None) -> Cuts:
    """The `cic` policy: CICFlowMeter's FlowGenerator.addPacket (module docstring). `idle_ns` is
    not CICFlowMeter's (it has none); when a user sets one it cuts like the flow timeout does."""
    n = kp.ts.shape[0]
    # CICFlowMeter's clock is whole microseconds (jnetpcap's timestampInMicros)
    ts = (kp.ts // 1000).tolist()
    active_us = None if active_ns is None else active_ns // 1000
    idle_us = None if idle_ns is None else idle_ns // 1000
    is_a, flags, proto, kp_ts = kp.is_a.tolist(), kp.flags.tolist(), kp.proto.tolist(), kp.ts.tolist()
    keep = [True] * n
    fwd = [True] * n
    starts: list[int] = []
    close: list[int] = []
    turned: list[bool] = []
    for lo, hi in zip(kp.key_starts[:-1].tolist(), kp.key_starts[1:].tolist()):
        first, src_a, fwd_fins, closed = lo, is_a[lo], 0, False
        starts.append(lo)
        turned.append(False)
        for k in range(lo + 1, hi):
            f = flags[k]
            timed_out = (active_us is not None and ts[k] - ts[first] > active_us) or \
                (idle_us is not None and ts[k] - ts[k - 1] >= idle_us)
            if closed or timed_out:
                close.append(kp_ts[k - 1] if closed else -1)
                starts.append(k)
                # after a timeout the new flow keeps the old orientation; after a close it is the
                # packet's own
                first, fwd_fins, closed = k, 0, False
                src_a = src_a if timed_out and not closed else is_a[k]
                fwd[k] = True  # firstPacket() counts the flow's first packet as forward
                # ... while the flow's source (its CSV identity) stays the old one (BasicFlow's
                # constructor sets src/dst after firstPacket)
                turned.append(is_a[k] != src_a)
                continue
            is_fwd = is_a[k] == src_a
            fwd[k] = is_fwd
            tcp = proto[k] == 6
            if tcp and f & TCP_FIN:
                if is_fwd:
                    fwd_fins += 1
                    keep[k] = fwd_fins == 1  # a second forward FIN is dropped
                else:
                    closed = True
            elif tcp and f & TCP_RST:
                closed = True
        close.append(kp_ts[hi - 1] if closed else -1)
    fwd_arr = np.asarray(fwd, dtype=bool)
    return Cuts(np.append(np.asarray(starts, dtype=np.int64), n), np.asarray(keep, dtype=bool), fwd_arr,
                np.asarray(close, dtype=np.int64), np.asarray(turned, dtype=bool))


def timeout_cuts(kp: KeyPackets, idle_ns: int | None, active_ns: int | None) -> Cuts:
    """The `timeout` policy (and the host-pair views, which run it with no timeout)."""
    starts = timeout_starts(kp.ts, kp.key_starts, idle_ns, active_ns)
    return _initiator_cuts(kp, starts, np.full(starts.shape[0] - 1, -1, dtype=np.int64))
