"""A small, realistic synthetic RUN_DIR (scapy pcaps, hand-made Plan, attack log, run.json).

Timeline (seconds after T0; attack windows are logged in attacks.jsonl as epoch times):
- HTTP sessions bs0 -> uav0:80 at 1, 11, 21, 31, 41, 51 and bs0 -> uav3:80 at 2, 12, ..., 52.
- Benign HTTP sessions uav1 -> uav0:80 at 5 and 45 (the flood's host pair OUTSIDE the window).
- DoS dos-0: uav1 SYN-floods uav0:80 in [20, 30): 50 SYNs, new source port each, every 5th
  answered by a SYN-ACK and an RST.
- Replay replay-0 by uav2: 3 packets of the uav3 -> bs0 session at 12 re-sent at ~13.5 with TTL-5
  and seq+k; each logged as an `inject` record.
- Blackhole blackhole-0 on uav3 in [40, 50): the fetch at 42 never gets an answer: its SYN and
  two retransmissions reach uav3's switch and go no further.
- Channel loss: one ACK of the bs0 -> uav3 session at 22 leaves bs0's switch and never
  reaches uav3's.
Links (every window): bs0-uav0, bs0-uav2, bs0-uav3, uav0-uav1. Capture points: s-bs0, s-uav0 and
s-uav3 see every packet to or from their node, the sender's switch at the send time and the
receiver's 50 us later (s-bs0 misses one packet of the session at 1); the replayer (uav2) is
not captured, so injected packets appear at s-bs0 only. `add_wormhole` turns a copy into a
wormhole run (uav2 detours uav0 <-> bs0 in window 0; s-uav2 sees the session at 1, +25 us).
"""

from __future__ import annotations

from pathlib import Path

from scapy.layers.inet import IP, TCP

from uavcas.events import AttackRate, AttackStart, AttackStop, Inject, attack_log_text
from uavcas.rundir import RunDir, RunInfo, RunOwner


def run_info(**fields) -> RunInfo:
    """A complete run.json of a finished run; `fields` override the defaults."""
    base = dict(config="test", seed=0, windows=12, window_s=5.0, prefix="synth", t0_unix=0.0, t_end_unix=60.0,
                wall_s=61.0, exit_status=0, exit_reason="ok", versions={}, tool_versions={}, kernel="test",
                kernel_features=None, shaper_backend=None, timings={}, window_applies=[], schedule=[],
                capture=[], capture_drops=0, packets_captured=0, http_clients=[], delay_daemon=None,
                attack_errors=[], wind_down_errors=[])
    return RunInfo(**{**base, **fields})
from scapy.layers.l2 import Ether
from scapy.packet import Raw
from scapy.utils import wrpcap

from uavcas.twin.load import plan_from_data
from uavcas.twin.model import Link, Node, Plan, Window, WormholeOverride

T0 = 1_700_000_000.0
CONFIG = "blackhole+dos=1000+replay=50,200,10,5,inc-4-1-image-logdist-adaptive-random-30-95"
IPS = {"uav0": "10.10.0.1", "uav1": "10.10.0.2", "uav2": "10.10.0.3", "uav3": "10.10.0.4", "bs0": "10.10.1.1"}
MACS = {n: f"02:00:00:00:00:{i:02x}" for i, n in enumerate(IPS)}
DOS_WINDOW = (20.0, 30.0)
BLACKHOLE_WINDOW = (40.0, 50.0)
N_FLOOD = 50
HOP_S = 50e-6  # sender's switch -> receiver's switch
LINKS = (("uav0", "bs0"), ("uav2", "bs0"), ("uav3", "bs0"), ("uav0", "uav1"))
LOST = {"src": "bs0", "dst": "uav3", "ip_id": 1208}  # an ACK of the session at 22 (channel loss)
WORMHOLE_WINDOW = (0.5, 3.0)


def _pkt(t, a, b, sport, dport, flags, seq=1000, ack=0, payload=b"", ttl=64, ip_id=1):
    p = (
        Ether(src=MACS[a], dst=MACS[b])
        / IP(src=IPS[a], dst=IPS[b], ttl=ttl, id=ip_id)
        / TCP(sport=sport, dport=dport, flags=flags, seq=seq, ack=ack)
    )
    if payload:
        p = p / Raw(payload)
    p.time = T0 + t
    return p


def http_session(t, client, server, sport, ip_id0=100):
    """12 packets: handshake, GET, 4 data segments with ACKs, FIN exchange."""
    c, s = 5000, 9000
    pk = [
        _pkt(t, client, server, sport, 80, "S", c, ip_id=ip_id0),
        _pkt(t + 0.01, server, client, 80, sport, "SA", s, c + 1, ip_id=ip_id0 + 1),
        _pkt(t + 0.02, client, server, sport, 80, "A", c + 1, s + 1, ip_id=ip_id0 + 2),
        _pkt(t + 0.03, client, server, sport, 80, "PA", c + 1, s + 1, b"GET /img.jpg HTTP/1.1\r\n\r\n",
             ip_id=ip_id0 + 3),
    ]
    for k in range(4):
        pk.append(_pkt(t + 0.05 + 0.02 * k, server, client, 80, sport, "A", s + 1 + 1000 * k, c + 26, b"x" * 1000,
                       ip_id=ip_id0 + 4 + k))
    pk.append(_pkt(t + 0.14, client, server, sport, 80, "A", c + 26, s + 4001, ip_id=ip_id0 + 8))
    pk.append(_pkt(t + 0.15, server, client, 80, sport, "FA", s + 4001, c + 26, ip_id=ip_id0 + 9))
    pk.append(_pkt(t + 0.16, client, server, sport, 80, "FA", c + 26, s + 4002, ip_id=ip_id0 + 10))
    pk.append(_pkt(t + 0.17, server, client, 80, sport, "A", s + 4002, c + 27, ip_id=ip_id0 + 11))
    return pk


def _link(a, b, detour=False):
    return Link(a=a, b=b, kind="air", distance_m=100.0, pathloss_db=80.0, snr_db=25.0, mcs=5, rate_mbps=50.0,
                delay_ms=HOP_S * 1000, loss=0.0, detour=detour)


def make_plan(wormhole: bool = False) -> Plan:
    names = list(IPS)
    nodes = [
        Node(name=n, kind="bs" if n.startswith("bs") else "uav", index=i, ip=IPS[n], mac=MACS[n])
        for i, n in enumerate(names)
    ]
    windows = [
        Window(index=k, t_s=5.0 * k, duration_s=5.0, positions={n: (0.0, 0.0, 50.0) for n in names},
               links=[_link(a, b) for a, b in LINKS]
               + ([_link("uav0", "uav2", detour=True)] if wormhole and k == 0 else []),
               routes=[],
               wormholes=[WormholeOverride(victim="uav0", attacker="uav2", bs="bs0", hops=["uav0", "uav2", "bs0"])]
               if wormhole and k == 0 else [])
        for k in range(12)
    ]
    attacks = [
        dict(attack_id="dos-0", family="dos", attackers=["uav1"], victims=["uav0"], start_s=DOS_WINDOW[0],
             stop_s=DOS_WINDOW[1], params={"interval_us": 1000}),
        dict(attack_id="replay-0", family="replay", attackers=["uav2"], victims=["uav3"], start_s=10.0, stop_s=20.0),
        dict(attack_id="blackhole-0", family="blackhole", attackers=["uav2"], victims=["uav3"],
             start_s=BLACKHOLE_WINDOW[0], stop_s=BLACKHOLE_WINDOW[1]),
    ]
    # read as a plan.json of the time before attacks carried specs: the families fill them in
    return plan_from_data(dict(config=CONFIG, seed=7, window_s=5.0, profile="test",
                               area_m=(1000.0, 1000.0, 30.0, 110.0),
                               nodes=nodes, windows=windows, attacks=attacks))


def _seen_at(pkts, node, extra_s=0.0, exclude=()):
    """Copies of the packets to or from `node`, timed as its switch sees them."""
    out = []
    for p in pkts:
        if IPS[node] in (p[IP].src, p[IP].dst) and not any(p is e for e in exclude):
            q = p.copy()
            q.time = p.time + (0.0 if p[IP].src == IPS[node] else HOP_S + extra_s)
            out.append(q)
    return out


def blackholed_fetch(t, sport, ip_id0):
    """A fetch to a blackholed UAV: the SYN and its retransmissions (1 s, then 2 s later)."""
    return [_pkt(t + dt, "bs0", "uav3", sport, 80, "S", 5000, ip_id=ip_id0 + k) for k, dt in enumerate((0.0, 1.0, 3.0))]


def build_run(run_dir: Path, run_id: str = "run-synth") -> Path:
    run_dir.mkdir(parents=True, exist_ok=True)
    (run_dir / "pcap").mkdir(exist_ok=True)
    pkts = []
    for k, t in enumerate((1, 11, 21, 31, 41, 51)):
        pkts += http_session(t, "bs0", "uav0", 40000 + k, ip_id0=100 * k)
    for k, t in enumerate((2, 12, 22, 32, 42, 52)):
        if t == 42:
            pkts += blackholed_fetch(t, 41000 + k, ip_id0=1000 + 100 * k)
        else:
            pkts += http_session(t, "bs0", "uav3", 41000 + k, ip_id0=1000 + 100 * k)
    for k, t in enumerate((5, 45)):
        pkts += http_session(t, "uav1", "uav0", 42000 + k, ip_id0=3000 + 100 * k)
    for i in range(N_FLOOD):
        t = DOS_WINDOW[0] + 0.1 + 0.19 * i
        sp = 1024 + i
        pkts.append(_pkt(t, "uav1", "uav0", sp, 80, "S", 77 + i, ip_id=5000 + i))
        if i % 5 == 0:
            pkts.append(_pkt(t + 0.001, "uav0", "uav1", 80, sp, "SA", 9, 78 + i, ip_id=6000 + i))
            pkts.append(_pkt(t + 0.002, "uav1", "uav0", sp, 80, "R", 78 + i, ip_id=7000 + i))
    # Replay: re-send the uav3 -> bs0 data segments of the session at 12 (ttl - 5, seq + k).
    orig = [p for p in http_session(12, "bs0", "uav3", 41001, ip_id0=1100)
            if p[IP].src == IPS["uav3"] and len(p[TCP].payload)][:3]
    injects, injected = [], []
    for k, o in enumerate(orig):
        r = o.copy()
        r[IP].ttl = o[IP].ttl - 5
        r[TCP].seq = o[TCP].seq + k + 1
        r.time = T0 + 13.5 + 0.1 * k
        pkts.append(r)
        injected.append(r)
        injects.append(Inject(attack_id="replay-0", family="replay", t_unix=float(r.time), src_ip=r[IP].src,
                              dst_ip=r[IP].dst, src_port=r[TCP].sport, dst_port=r[TCP].dport, protocol=6,
                              ip_id=r[IP].id, ttl=r[IP].ttl, seq=r[TCP].seq, orig_seq=o[TCP].seq,
                              orig_ttl=o[IP].ttl))
    pkts.sort(key=lambda p: float(p.time))
    bs = _seen_at(pkts, "bs0")
    bs = [p for p in bs if not (p[IP].id == 3 and p[IP].dst == IPS["uav0"])]  # one packet missed at s-bs0
    lost = [p for p in pkts if (p[IP].src, p[IP].dst, p[IP].id) == (IPS[LOST["src"]], IPS[LOST["dst"]], LOST["ip_id"])]
    assert len(lost) == 1
    u3 = _seen_at(pkts, "uav3", exclude=injected + lost)  # the replayer sends from uav2's switch
    wrpcap(str(run_dir / "pcap" / "s-bs0.pcap"), sorted(bs, key=lambda p: float(p.time)))
    wrpcap(str(run_dir / "pcap" / "s-uav0.pcap"), sorted(_seen_at(pkts, "uav0"), key=lambda p: float(p.time)))
    wrpcap(str(run_dir / "pcap" / "s-uav3.pcap"), sorted(u3, key=lambda p: float(p.time)))

    plan = make_plan()
    (run_dir / "plan.json").write_text(plan.to_json())
    def start(aid, fam, attacker, victim, window, **params):
        return AttackStart(attack_id=aid, family=fam, attackers=[attacker], attacker_ips=[IPS[attacker]],
                           victims=[victim], victim_ips=[IPS[victim]], t_unix=T0 + window[0], params=params,
                           planned_start_s=window[0], planned_stop_s=window[1])

    log = [
        start("replay-0", "replay", "uav2", "uav3", (10.0, 20.0)),
        *injects,
        AttackStop(attack_id="replay-0", family="replay", t_unix=T0 + 20.0),
        start("dos-0", "dos", "uav1", "uav0", DOS_WINDOW, interval_us=1000),
        AttackRate(attack_id="dos-0", family="dos", attacker="uav1", measured_pps=5.2, nominal_pps=1000,
                   hping_interval_us=1000, syn_count=50, seconds=9.6, restarts=0, intervals_us=[1000],
                   victim_ip=IPS["uav0"], t_unix=T0 + DOS_WINDOW[1]),
        AttackStop(attack_id="dos-0", family="dos", t_unix=T0 + DOS_WINDOW[1]),
        start("blackhole-0", "blackhole", "uav2", "uav3", BLACKHOLE_WINDOW),
        AttackStop(attack_id="blackhole-0", family="blackhole", t_unix=T0 + BLACKHOLE_WINDOW[1]),
    ]
    (run_dir / "attacks.jsonl").write_text(attack_log_text(log))
    # as a real run: the marker first (with t0 once the run reached it), run.json last
    RunDir(run_dir).write_owner(RunOwner(prefix="synth", pid=1, started_unix=T0 - 5.0, t0_unix=T0))
    (run_dir / "run.json").write_text(run_info(run_id=run_id, t0_unix=T0, config=CONFIG, seed=7).to_json())
    return run_dir


def add_wormhole(run_dir: Path) -> Path:
    """Make `run_dir` (a copy of build_run's) a run where uav2 detours uav0 <-> bs0 during
    WORMHOLE_WINDOW (window 0): the plan's detour, s-uav2's capture of the session at 1, the log."""
    from uavcas.rundir import RunDir

    (run_dir / "plan.json").write_text(make_plan(wormhole=True).to_json())
    session = http_session(1, "bs0", "uav0", 40000, ip_id0=0)
    mid = []
    for p in session:
        q = p.copy()
        q.time = p.time + HOP_S / 2
        mid.append(q)
    wrpcap(str(run_dir / "pcap" / "s-uav2.pcap"), mid)
    recs = RunDir(run_dir).read_attacks()
    recs += [AttackStart(attack_id="wormhole-0", family="wormhole", attackers=["uav2"], attacker_ips=[IPS["uav2"]],
                         victims=["uav0"], victim_ips=[IPS["uav0"]], t_unix=T0 + WORMHOLE_WINDOW[0], params={},
                         planned_start_s=WORMHOLE_WINDOW[0], planned_stop_s=WORMHOLE_WINDOW[1]),
             AttackStop(attack_id="wormhole-0", family="wormhole", t_unix=T0 + WORMHOLE_WINDOW[1])]
    (run_dir / "attacks.jsonl").write_text(attack_log_text(recs))
    return run_dir


# MAVLink (uavcas.mavlink_capture): real MAVLink 2 frames packed by pymavlink, in UDP datagrams.
MAV_UAV_PORT, MAV_GCS_PORT = 14555, 14550  # the vehicle's and the ground station's (MAVLink's default)
MAV_LAT, MAV_LON = 473977420, 85455940  # degE7
MAV_BLACKHOLED_T = 43.0  # bs0's COMMAND_LONG to uav3 inside the blackhole window


def _mav(sysid: int, compid: int):
    from pymavlink.dialects.v20 import ardupilotmega as mavlink2

    return mavlink2.MAVLink(None, srcSystem=sysid, srcComponent=compid)


def mavlink_datagrams() -> list[tuple[float, str, str, int, int, bytes]]:
    """(t, src, dst, sport, dport, payload) of the synthetic MAVLink traffic: uav0 (sysid 1) to the
    ground station bs0 (sysid 255) and back, and one command to the blackholed uav3."""
    uav, gcs = _mav(1, 1), _mav(255, 190)
    hb = uav.heartbeat_encode(2, 3, 81, 0, 4).pack(uav)
    pos = uav.global_position_int_encode(3000, MAV_LAT, MAV_LON, 584000, 50000, 120, -50, 7, 9000).pack(uav)
    cmd = gcs.command_long_encode(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0).pack(gcs)
    bad = bytearray(pos)
    bad[-1] ^= 0xFF  # the CRC's high byte: the frame is whole, its checksum wrong
    to_gcs, to_uav = (MAV_UAV_PORT, MAV_GCS_PORT), (MAV_GCS_PORT, MAV_UAV_PORT)
    return [
        (3.0, "uav0", "bs0", *to_gcs, hb),
        (3.1, "uav0", "bs0", *to_gcs, pos),
        (3.2, "bs0", "uav0", *to_uav, cmd),
        (3.3, "uav0", "bs0", *to_gcs, hb + pos),  # two messages in one datagram
        (3.4, "uav0", "bs0", *to_gcs, bytes(bad)),
        (3.5, "uav0", "bs0", *to_gcs, b"not a mavlink frame"),
        (3.6, "uav0", "bs0", 40002, 5600, b"\x80\x60" + bytes(30)),  # RTP video: another port, not decoded
        (MAV_BLACKHOLED_T, "bs0", "uav3", *to_uav, cmd),
    ]


def add_mavlink(run_dir: Path) -> Path:
    """Add `mavlink_datagrams` to a copy of build_run's captures, each seen at its sender's switch
    and HOP_S later at its receiver's (every capture point of the run sees both ends here)."""
    from scapy.layers.inet import UDP
    from scapy.utils import rdpcap

    new = []
    for k, (t, a, b, sport, dport, payload) in enumerate(mavlink_datagrams()):
        p = Ether(src=MACS[a], dst=MACS[b]) / IP(src=IPS[a], dst=IPS[b], ttl=64, id=8000 + k) \
            / UDP(sport=sport, dport=dport) / Raw(payload)
        p.time = T0 + t
        new.append(p)
    for node in ("bs0", "uav0", "uav3"):
        path = run_dir / "pcap" / f"s-{node}.pcap"
        pkts = list(rdpcap(str(path))) + _seen_at(new, node)
        wrpcap(str(path), sorted(pkts, key=lambda p: float(p.time)))
    return run_dir
