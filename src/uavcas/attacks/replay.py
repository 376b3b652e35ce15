"""Replay: an attacker re-sends captured packets of the victim, with rewritten TTL and sequence.

- token `replay=<buffer>,<delay_ms>,<pps>,<ttl_dec>,<inc|rand|zero>`;
- schedule: one attacker;
- executor: the replayer process (`attacks.tools.replayer`) is started before t0 (scapy takes a
  second to import) and sees nothing of the victim until `start` mirrors the victim's host port
  to the attacker's: tc act_mirred copies every IPv4 frame the victim sends (ingress of its host
  port) and receives (egress) out of the attacker's host port, so the attacker's `eth0` sees the
  victim's traffic wherever the attacker is. At stop the mirror is removed and the process ended
  before `stop` is logged; its `inject` records land in the attack log;
- truth (effect `replay`, label source "replay-injections"): a packet that matches an `inject`
  record of the attack on (src_ip, dst_ip, protocol, ip_id, ttl, the ports where recorded, and
  seq for TCP) captured within MATCH_TOLERANCE_S of the record's t_unix: an injected copy
  (packet-exact; the originals it copied stay benign). A record without seq (UDP) marks the one
  matching transmission nearest its time (`injected_packets`);
- provoked (effect `provoked` with this family): the answers to an injected copy, matched to it
  packet to packet (`attacks.answers`), after it and within ANSWER_WITHIN_S:
  (a) a copy of a SYN (ACK clear): the SYN-ACK on its 5-tuple reversed with ack = its seq + 1,
      and the RST its spoofed source answers that SYN-ACK with (it never sent the SYN): on the
      copy's 5-tuple, RST set, seq = the copy's seq + 1 (as the flood's rule (b));
  (b) the RST answering a copy (its 5-tuple reversed, RST set), as RFC 793 builds it: seq = the
      copy's ack when the copy had ACK set, else ACK set and ack = the copy's seq + its payload
      length (+1 for SYN, +1 for FIN);
  (c) ICMP errors to the copy's source quoting it, IP id and TTL included (the copy differs
      from its original there);
  (d) for a live connection, the receiver's immediate duplicate / challenge ACK (RFC 793, RFC
      5961: an old or out-of-window segment is answered with an ACK at once): the pure ACK (no
      payload, no SYN/FIN/RST) on the copy's 5-tuple reversed whose nearest preceding packet of
      the copy's direction at the same capture point is the copy, within DUP_ACK_WITHIN_S of it.
      The point is the ACK's first (its sender's switch, where the copy was just delivered):
      further along, the order of the two directions tells nothing about cause.
"""

from __future__ import annotations

import json
import signal
import sys
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pandas as pd
from pydantic import Field

from uavcas.emulation import kernel
from uavcas.emulation.apps.procs import spawn, wait_for
from uavcas.flows.packets import address_to_words
from uavcas.labels.attacklog import AttackLog
from uavcas.network.naming import Naming
from uavcas.scenario_model import ScenarioError, SpecBase, choice, int_field
from uavcas.vocabulary import SEQ_MODES, SeqMode

from .answers import (
    ANSWER_WITHIN_S,
    TCP_ACK,
    TCP_FIN,
    TCP_RST,
    TCP_SYN,
    answers,
    icmp_errors_quoting,
    payload_len,
    tcp_flags_are,
)
from .base import AttackExecutor, AttackFamily, SyntheticPackets, TruthContext
from .registry import register
from .tools import tool_path

if TYPE_CHECKING:  # types only: the twin's and labels' package __init__s load this registry
    from collections.abc import Callable

    from uavcas.labels.attacklog import AttackLog, AttackWindow
    from uavcas.twin.model import Attack

MATCH_TOLERANCE_S = 1.0
# A duplicate or challenge ACK leaves at once (Linux: tcp_send_dupack / tcp_send_challenge_ack,
# no delayed ACK); at the receiver's switch it follows the copy by the host's processing time.
# 1 s leaves room for a loaded host and excludes a keep-alive or a later ACK of the connection.
DUP_ACK_WITHIN_S = 1.0
READY_S = 20.0  # the replayer's start-up (scapy import) must finish within this


class ReplaySpec(SpecBase):
    family: Literal["replay"] = "replay"
    buffer_pkts: int = Field(gt=0)
    delay_ms: int = Field(ge=0)
    rate_pps: int = Field(gt=0)
    ttl_dec: int = Field(ge=0, le=254)
    seq_mode: SeqMode

    def token(self) -> str:
        return (
            f"replay={self.buffer_pkts},{self.delay_ms},{self.rate_pps},"
            f"{self.ttl_dec},{self.seq_mode}"
        )


# The paper's conservative replay, used for plan attacks written without parameters.
_DEFAULT = {"buffer_pkts": 50, "delay_ms": 200, "rate_pps": 10, "ttl_dec": 5, "seq_mode": "inc"}


def mirror_lines(victim_port: str, attacker_port: str) -> list[str]:
    act = f"action mirred egress mirror dev {attacker_port}"
    return [f"qdisc replace dev {victim_port} clsact",
            f"filter add dev {victim_port} ingress protocol ip prio 7 u32 match u32 0 0 {act}",
            f"filter add dev {victim_port} egress protocol ip prio 7 u32 match u32 0 0 {act}"]


def mirror_on(fabric_ns: str, victim_port: str, attacker_port: str) -> None:
    kernel.run_batch("tc", fabric_ns, mirror_lines(victim_port, attacker_port))


def mirror_off(fabric_ns: str, victim_port: str) -> None:
    # Only the replay puts a clsact on a host port; deleting it removes both filters.
    kernel.run(["tc", "-n", fabric_ns, "qdisc", "del", "dev", victim_port, "clsact"], check=False)


@register
class Replay(AttackFamily):
    name = "replay"
    spec = ReplaySpec
    usage = "replay=<buf>,<ms>,<pps>,<ttl>,<mode>"
    truth_rule = ("a packet matching an inject record (addresses, protocol, ports, IP id, TTL, TCP seq) within "
                  f"{MATCH_TOLERANCE_S:g} s of it (an injected copy; without a seq, as UDP, the nearest one)")
    provoked_rule = ("answers to an injected copy on its 5-tuple reversed: the SYN-ACK with ack = its seq + 1 (a "
                     "copied SYN, and the RST on the copy's own 5-tuple with seq = its seq + 1); the RST with seq = "
                     "its ack (copy with ACK) or ack = its seq + length (+1 SYN/FIN); ICMP errors quoting it (IP id "
                     f"and TTL included); each within {ANSWER_WITHIN_S:g} s after it; and the pure ACK whose nearest "
                     "preceding packet of the copy's direction at the same capture point is the copy, within "
                     f"{DUP_ACK_WITHIN_S:g} s")
    python_modules = ("scapy",)

    def parse(self, arg: str | None, tok: str) -> ReplaySpec:
        parts = arg.split(",") if arg is not None else []
        if len(parts) != 5:
            raise ScenarioError(
                "field 'attacks': replay needs 5 values "
                f"<buffer>,<delay_ms>,<pps>,<ttl_dec>,<inc|rand|zero>, got {tok!r}"
            )
        buf, delay, pps, ttl, mode = parts
        return ReplaySpec(
            buffer_pkts=int_field("attacks.replay.buffer", buf, 1, 1_000_000),
            delay_ms=int_field("attacks.replay.delay_ms", delay, 0, 3_600_000),
            rate_pps=int_field("attacks.replay.pps", pps, 1, 1_000_000),
            ttl_dec=int_field("attacks.replay.ttl_dec", ttl, 0, 254),
            seq_mode=choice("attacks.replay.seq_mode", mode, SEQ_MODES),
        )

    def spec_from_params(self, params: dict[str, Any]) -> ReplaySpec:
        return ReplaySpec(**{k: params.get(k, v) for k, v in _DEFAULT.items()})

    # executor ----------------------------------------------------------------------------------
    def prepare(self, ex: "AttackExecutor", attack: "Attack") -> None:
        s: ReplaySpec = ex.spec(attack)  # type: ignore[assignment]
        for attacker in attack.attackers:
            log = ex.log_dir / f"inject-{attack.attack_id}-{attacker}.jsonl"
            log.parent.mkdir(parents=True, exist_ok=True)
            log.write_text("")
            argv = [sys.executable, str(tool_path("replayer")), "--iface", Naming.HOST_IF,
                    "--victim", ex.ip(attack.victims[0]), "--attacker-ip", ex.ip(attacker),
                    "--buffer", str(s.buffer_pkts), "--delay-ms", str(float(s.delay_ms)),
                    "--rate-pps", str(float(s.rate_pps)), "--ttl-dec", str(s.ttl_dec),
                    "--seq-mode", s.seq_mode, "--seconds", str(ex.duration_s + 30),
                    "--seed", str(ex.plan.seed), "--index", str(ex.index(attacker)), "--attack-id", attack.attack_id,
                    "--family", attack.family, "--log", str(log)]
            proc = spawn(lambda av, t, **kw: ex.emu.popen(attacker, av, t, **kw),
                         f"replayer-{attack.attack_id}-{attacker}", argv, ex.log_dir, ex.duration_s + 40)
            ex.state[f"{attack.attack_id}/{attacker}"] = proc
            ex.add_process(proc, log)
        for attacker in attack.attackers:
            proc = ex.state[f"{attack.attack_id}/{attacker}"]
            if not wait_for(lambda: "ready" in proc.stdout() or not proc.alive(), READY_S, 0.05) \
                    or not proc.alive():
                raise RuntimeError(f"{attack.attack_id}: replayer did not start: {proc.stderr().strip()[-300:]}")

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        v = attack.victims[0]
        for x in attack.attackers:
            proc = ex.state[f"{attack.attack_id}/{x}"]
            if not proc.alive():
                raise RuntimeError(f"replayer of {x} is not running: {proc.stderr().strip()[-300:]}")
            mirror_on(ex.emu.fabric_ns, ex.emu.switch(v).host_port, ex.emu.switch(x).host_port)
        return {"mirror": {"from": ex.emu.switch(v).host_port,
                           "to": [ex.emu.switch(x).host_port for x in attack.attackers]}}

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        return self.halt(ex, attack)()

    def halt(self, ex: "AttackExecutor", attack: "Attack") -> Callable[[], dict[str, Any]]:
        mirror_off(ex.emu.fabric_ns, ex.emu.switch(attack.victims[0]).host_port)
        procs = {x: ex.state[f"{attack.attack_id}/{x}"] for x in attack.attackers}
        for proc in procs.values():
            if proc.alive():
                proc.popen.send_signal(signal.SIGTERM)

        def finish() -> dict[str, Any]:
            # the stop record follows the replayers' exit: a buffered copy may leave until then
            stats = {}
            for x, proc in procs.items():
                proc.stop(signal.SIGTERM, grace_s=3.0)
                for line in proc.stdout().splitlines():
                    if line.startswith("{"):
                        stats[x] = json.loads(line).get("stats")
            return {"replayer_stats": stats}

        return finish

    # ground truth ------------------------------------------------------------------------------
    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        ids = {w.attack_id for w in windows}
        mine = AttackLog(injections=tuple(i for i in ctx.log.injections if i.attack_id in ids))
        return ctx.spread(injected_packets(ctx.packets, mine))

    def provoked(self, ctx: "TruthContext", windows: list["AttackWindow"], made: np.ndarray) -> np.ndarray:
        p = ctx.packets
        flags = p["tcp_flags"]
        seq = p["tcp_seq"].astype(np.int64)
        syn = made & tcp_flags_are(p, TCP_SYN, TCP_SYN | TCP_ACK)
        with_ack = made & tcp_flags_are(p, TCP_ACK, TCP_ACK)
        without_ack = made & tcp_flags_are(p, 0, TCP_ACK)
        # RFC 793 segment length: payload, plus one for each of SYN and FIN
        seg_len = payload_len(p) + ((flags & TCP_SYN) != 0) + ((flags & TCP_FIN) != 0)
        synack = tcp_flags_are(p, TCP_SYN | TCP_ACK, TCP_SYN | TCP_ACK | TCP_RST)
        rst = tcp_flags_are(p, TCP_RST, TCP_RST)
        rst_ack = tcp_flags_are(p, TCP_RST | TCP_ACK, TCP_RST | TCP_ACK)
        hit = (answers(p, syn, synack, reverse=True, field="tcp_ack", value=seq[syn] + 1)
               | answers(p, syn, rst, reverse=False, field="tcp_seq", value=seq[syn] + 1)
               | answers(p, with_ack, rst, reverse=True, field="tcp_seq", value=p["tcp_ack"][with_ack])
               | answers(p, without_ack, rst_ack, reverse=True, field="tcp_ack",
                         value=seq[without_ack] + seg_len[without_ack])
               | icmp_errors_quoting(p, made, exact=True)
               | dup_acks(p, made, ctx.followed.hop == 0))
        return ctx.spread(hit) & ~made

    def synthetic_change(self, rng: np.random.Generator, packets: SyntheticPackets, made: bool) -> SyntheticPackets:
        """Copies of 15 % of the flow's packets (at least one), each 10-500 us after its original
        (near-zero gaps), in time order."""
        t, size, d, flags = packets
        k = max(1, int(0.15 * len(t)))
        pick = np.sort(rng.choice(len(t), k, replace=False))
        t2 = t[pick] + rng.uniform(1e-5, 5e-4, k)
        order = np.argsort(np.concatenate([t, t2]), kind="stable")

        def cat(a: np.ndarray, copies: np.ndarray) -> np.ndarray:
            return np.concatenate([a, copies])[order]

        return cat(t, t2), cat(size, size[pick]), cat(d, d[pick]), cat(flags, flags[pick])


def dup_acks(p, copies: np.ndarray, first: np.ndarray, within_s: float = DUP_ACK_WITHIN_S) -> np.ndarray:
    """Pure ACKs answering a copy at once (module docstring, (d)): on the copy's 5-tuple
    reversed, and at the ACK's `first` observation (its sender's switch) the nearest earlier
    packet of the copy's direction is a copy, at most `within_s` before."""
    n = len(p)
    out = np.zeros(n, dtype=bool)
    c = np.flatnonzero(copies & (p["proto"] == 6))
    if c.shape[0] == 0:
        return out
    ends = ["src_hi", "src_lo", "dst_hi", "dst_lo", "sport", "dport"]
    rev = ["dst_hi", "dst_lo", "src_hi", "src_lo", "dport", "sport"]
    convs = pd.DataFrame({k: p[k][c] for k in ends}).drop_duplicates().reset_index(drop=True)
    convs["conv"] = np.arange(len(convs))
    tcp = np.flatnonzero(p["proto"] == 6)
    rows = pd.DataFrame({k: p[k][tcp] for k in ends})
    rows["row"] = tcp
    # the rows of each copy's connection at every capture point: its direction (+1) and back (-1)
    fwd = rows.merge(convs, on=ends, how="inner").assign(dir=1)
    back = rows.merge(convs.rename(columns=dict(zip(ends, rev))), on=ends, how="inner").assign(dir=-1)
    both = pd.concat([fwd, back], ignore_index=True)[["row", "conv", "dir"]]
    r = both["row"].to_numpy()
    both["point"], both["ts"] = p["point"][r], p["ts_ns"][r]
    both = both.sort_values(["conv", "point", "ts", "row"], kind="stable")
    r, d = both["row"].to_numpy(), both["dir"].to_numpy()
    group = both["conv"].to_numpy().astype(np.int64) * (1 << 16) + both["point"].to_numpy().astype(np.int64)
    pos = np.arange(r.shape[0])
    # position of the nearest earlier row of the copy's direction (any group), then kept if in the same group
    last_fwd = np.maximum.accumulate(np.where(d == 1, pos, -1))
    prev = np.maximum(last_fwd, 0)
    ok = (d == -1) & (last_fwd >= 0) & (group[prev] == group)
    ts = both["ts"].to_numpy()
    ok &= copies[r[prev]] & (ts - ts[prev] <= round(within_s * 1e9))
    pure = tcp_flags_are(p, TCP_ACK, TCP_ACK | TCP_SYN | TCP_FIN | TCP_RST) & (payload_len(p) == 0)
    ok &= pure[r] & first[r]
    out[r[ok]] = True
    return out


def injected_packets(p, log: "AttackLog") -> np.ndarray:
    """Mask of packets that match an inject record (see the module docstring).

    The key: addresses, protocol, IP id and TTL, the ports where the record has them (TCP, UDP),
    and the TCP sequence number. A TCP record marks every observation of its key within
    MATCH_TOLERANCE_S (the rewritten seq makes the key the copy's alone). A record without a
    sequence number (UDP: MAVLink on 14550, RTP video on 5600) marks only the matching observation
    nearest its time (the rest of that transmission follows through `TruthContext.spread`): an
    unconnected UDP socket sends IP id 0 with DF, so with the TTL left as it was (ttl_dec 0) the
    original and the other copies of one stream carry the very same key within the tolerance."""
    mask = np.zeros(len(p), dtype=bool)
    if not log.injections or len(p) == 0:
        return mask
    words = [(address_to_words(i.src_ip), address_to_words(i.dst_ip)) for i in log.injections]
    inj = pd.DataFrame(
        {
            "src": [s[1] for s, _ in words],
            "dst": [d[1] for _, d in words],
            "src_hi": [s[0] for s, _ in words],
            "dst_hi": [d[0] for _, d in words],
            "proto": [i.protocol for i in log.injections],
            "ip_id": [i.ip_id for i in log.injections],
            "ttl": [i.ttl for i in log.injections],
            "seqk": [-1 if (i.seq is None or i.protocol != 6) else i.seq for i in log.injections],
            "rec_sport": [-1 if i.src_port is None else i.src_port for i in log.injections],
            "rec_dport": [-1 if i.dst_port is None else i.dst_port for i in log.injections],
            "t_inj": [i.t_unix for i in log.injections],
        }
    ).astype({"src": np.uint64, "dst": np.uint64, "src_hi": np.uint64, "dst_hi": np.uint64, "proto": np.int64,
              "ip_id": np.int64, "ttl": np.int64, "seqk": np.int64, "rec_sport": np.int64, "rec_dport": np.int64})
    inj["rec"] = np.arange(len(inj))
    cand = np.flatnonzero(np.isin(p["src_lo"], inj["src"].to_numpy()))
    pk = pd.DataFrame(
        {
            "row": cand,
            "src": p["src_lo"][cand],
            "dst": p["dst_lo"][cand],
            "src_hi": p["src_hi"][cand],
            "dst_hi": p["dst_hi"][cand],
            "proto": p["proto"][cand].astype(np.int64),
            "ip_id": p["ip_id"][cand].astype(np.int64),
            "ttl": p["ttl"][cand].astype(np.int64),
            "seqk": np.where(p["proto"][cand] == 6, p["tcp_seq"][cand].astype(np.int64), -1),
            "sport": p["sport"][cand].astype(np.int64),
            "dport": p["dport"][cand].astype(np.int64),
            "ts": p["ts_s"][cand],
        }
    )
    m = pk.merge(inj, on=["src", "dst", "src_hi", "dst_hi", "proto", "ip_id", "ttl", "seqk"], how="inner")
    m["dt"] = (m["ts"] - m["t_inj"]).abs()
    ports = (((m["rec_sport"] < 0) | (m["sport"] == m["rec_sport"]))
             & ((m["rec_dport"] < 0) | (m["dport"] == m["rec_dport"])))
    m = m[ports & (m["dt"] <= MATCH_TOLERANCE_S)]
    exact = m["seqk"] >= 0
    nearest = m[~exact].sort_values(["rec", "dt", "ts"], kind="stable").drop_duplicates("rec", keep="first")
    mask[m.loc[exact, "row"].to_numpy()] = True
    mask[nearest["row"].to_numpy()] = True
    return mask
