"""Root integration tests of traffic, attacks, capture and `uavcas run` on real namespaces.

Small hand-made plans (3-5 nodes, 2-3 windows of 3-4 s). Skipped with a reason without root.
The pcaps are read back with dpkt (uavcas.testing.runcheck), independently of
uavcas.flows.
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest

from helpers.runplans import attack, link, make_plan, nodes
from uavcas.emulation import kernel
from uavcas.emulation.attacks import AttackExecutor
from uavcas.emulation.emulation import Emulation
from uavcas.emulation.runner import realize
from uavcas.testing import runcheck as rc

pytestmark = pytest.mark.root
REPO = Path(__file__).resolve().parents[2]
UAVCAS = str(REPO / ".venv" / "bin" / "uavcas")


# probes (in-process sockets created inside the namespaces) -----------------------------------
def listen(emu, node: str, port: int) -> socket.socket:
    with kernel.in_netns(emu.ns(node)):
        s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind((emu.ip(node), port))
    s.listen(64)
    return s


def tcp_ok(emu, src: str, dst: str, port: int, timeout_s: float = 1.0) -> bool:
    with kernel.in_netns(emu.ns(src)):
        s = socket.socket()
    s.settimeout(timeout_s)
    try:
        return s.connect_ex((emu.ip(dst), port)) == 0
    except OSError:
        return False
    finally:
        s.close()


def arp_reply(emu, src: str, dst: str, timeout_s: float = 1.0) -> bool:
    """Unicast ARP who-has from src to dst's MAC (the fabric floods no broadcast); a reply?"""
    from scapy.layers.l2 import ARP, Ether

    me, peer = emu.plan.node(src), emu.plan.node(dst)
    with kernel.in_netns(emu.ns(src)):
        s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(0x0806))
    try:
        s.bind(("eth0", 0x0806))
        s.settimeout(0.2)
        s.send(bytes(Ether(src=me.mac, dst=peer.mac) / ARP(op=1, hwsrc=me.mac, psrc=me.ip, pdst=peer.ip)))
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            try:
                f = Ether(s.recv(2048))
            except socket.timeout:
                continue
            if ARP in f and f[ARP].op == 2 and f[ARP].psrc == peer.ip:
                return True
        return False
    finally:
        s.close()


def ping_avg_ms(emu, src: str, dst: str, n: int = 6) -> float:
    r = emu.run(src, ["ping", "-c", str(n), "-i", "0.2", "-q", "-W", "1", emu.ip(dst)], timeout_s=10)
    m = re.search(r"= [\d.]+/([\d.]+)/", r.stdout)
    assert m, r.stdout + r.stderr
    return float(m.group(1))


def assert_nothing_left(prefix: str) -> None:
    assert not [ns for ns in kernel.netns_list() if ns.startswith(prefix + "-")]
    assert not Path(f"/run/uavcas/{prefix}").exists()
    ps = subprocess.run(["ps", "-eo", "args"], capture_output=True, text=True).stdout
    assert f"/run/uavcas/{prefix}/" not in ps and f"{prefix}-" not in ps


# attacks driven directly (probing inside the window) ------------------------------------------
def test_blackhole_drops_data_keeps_arp_and_ends(tmp_path):
    p = make_plan(nodes(2), [link("uav0", "uav1"), link("uav1", "bs0")],
                  [attack("blackhole", ["uav1"], "uav0", 0.0, 10.0)], n_windows=1, window_s=10.0)
    with Emulation(p) as emu:
        emu.apply_window(0)
        ex = AttackExecutor(emu, p, tmp_path, p.duration_s)
        ex.window = p.windows[0]
        servers = [listen(emu, "bs0", 8080), listen(emu, "uav0", 8080)]
        assert tcp_ok(emu, "uav0", "bs0", 8080) and tcp_ok(emu, "bs0", "uav0", 8080)
        ex.start(p.attacks[0])
        assert arp_reply(emu, "uav0", "bs0") and arp_reply(emu, "bs0", "uav0")  # ARP still resolves
        assert not tcp_ok(emu, "uav0", "bs0", 8080)  # both directions of the victim's IPv4 dropped
        assert not tcp_ok(emu, "bs0", "uav0", 8080)
        assert tcp_ok(emu, "uav1", "bs0", 8080)  # others unaffected
        rec = ex.stop(p.attacks[0])
        assert rec.dropped_frames >= 2
        assert tcp_ok(emu, "uav0", "bs0", 8080) and tcp_ok(emu, "bs0", "uav0", 8080)
        for s in servers:
            s.close()
    assert [r.event for r in ex.records] == ["start", "stop"]


def test_wormhole_adds_the_attacker_hop_to_the_victims_rtt(tmp_path):
    links = [link("uav0", "bs0", delay_ms=1.0), link("uav0", "uav1", delay_ms=5.0), link("uav1", "bs0", delay_ms=5.0)]
    p = make_plan(nodes(2), links, [attack("wormhole", ["uav1"], "uav0", 0.0, 10.0)], n_windows=1, window_s=10.0,
                  routes=[["uav0", "bs0"], ["uav1", "bs0"]], wormholes=[("uav0", "uav1", "bs0")])
    with Emulation(p) as emu:
        ex = AttackExecutor(emu, p, tmp_path, p.duration_s)
        w = p.windows[0]
        ex.window = w
        emu.apply_links(w.links, [r.hops for r in w.routes], ex.wormholes_for(w), window_index=0)
        before = ping_avg_ms(emu, "bs0", "uav0")
        rec = ex.start(p.attacks[0])
        assert rec.paths["uav0>bs0"] == ["uav0", "uav1", "bs0"] and not rec.rejected
        during = ping_avg_ms(emu, "bs0", "uav0")
        ex.stop(p.attacks[0])
        after = ping_avg_ms(emu, "bs0", "uav0")
    # direct: 2 x 1 ms; through the attacker: 2 x (5 + 5) ms
    assert before < 5 and after < 5, (before, after)
    assert during - before > 14, (before, during)


# whole runs --------------------------------------------------------------------------------
def test_replay_injects_with_decremented_ttl_never_replays_of_replays(tmp_path):
    ns = nodes(2)
    p = make_plan(ns, [link("uav0", "bs0"), link("uav1", "bs0")],
                  [attack("replay", ["uav1"], "uav0", 1.0, 7.0, buffer_pkts=100, delay_ms=100, rate_pps=20,
                          ttl_dec=3, seq_mode="rand")], n_windows=2, window_s=4.0)
    art = realize(p, tmp_path / "r")
    assert art.exit_status == 0, art.exit_reason
    start, stop, _ = rc.windows(art.out_dir)["replay-0"]
    inj = [r for r in rc.attack_log(art.out_dir) if r["event"] == "inject"]
    assert len(inj) >= 0.8 * 20 * (stop - start - 0.1)  # the configured 20 pps, on average
    assert all(start <= r["t_unix"] < stop for r in inj)
    assert all(r["orig_ttl"] == 64 and r["ttl"] == 61 for r in inj)  # originals only, TTL - 3
    assert sum(r["seq"] != r["orig_seq"] for r in inj if r["seq"] is not None) >= 0.9 * len(inj)
    pk = [x for f in art.pcaps for x in rc.read_pcap(f)]
    seen = {(x.src, x.dst, x.ip_id, x.ttl, x.seq) for x in pk}
    found = [r for r in inj if (r["src_ip"], r["dst_ip"], r["ip_id"], r["ttl"], r["seq"]) in seen]
    assert len(found) >= 0.98 * len(inj)
    assert not [x for x in pk if x.ttl == 64 - 2 * 3]  # no replay of a replay anywhere
    assert all(x.ttl in (64, 61) for x in pk)
    assert_nothing_left(art.run_info.prefix)


def test_ddos_from_two_attackers_at_the_nominal_rate(tmp_path):
    ns = nodes(3)
    links = [link("uav0", "bs0"), link("uav1", "bs0"), link("uav2", "bs0")]
    p = make_plan(ns, links, [attack("ddos", ["uav1", "uav2"], "uav0", 1.0, 6.0)], n_windows=2, window_s=4.0)
    art = realize(p, tmp_path / "r")
    assert art.exit_status == 0, art.exit_reason
    start, stop, rec = rc.windows(art.out_dir)["ddos-0"]
    until = rc.crossed(art.out_dir)["ddos-0"]  # the last SYN left at stop; it may cross until then
    victim = rc.read_pcap(art.out_dir / "pcap" / "s-uav0.pcap")
    rates = {r["attacker"]: r for r in rc.attack_log(art.out_dir) if r["event"] == "rate"}
    assert sorted(rates) == ["uav1", "uav2"] and all(r["restarts"] == 0 for r in rates.values())
    # one hping3 per attacker for the whole attack: its source ports never repeat
    assert len(list((art.out_dir / "logs").glob("hping3-*.err"))) == 2
    pcaps = {pc.stem: rc.read_pcap(pc) for pc in (art.out_dir / "pcap").glob("s-*.pcap")}
    v_ip = rec["victim_ips"][0]
    for name, ip in zip(rec["attackers"], rec["attacker_ips"]):
        own = [x for x in pcaps[f"s-{name}"] if rc.is_syn(x) and x.src == ip and x.dst == v_ip]
        assert len({x.sport for x in own}) == len(own) == rates[name]["syn_count"]  # the nft count is exact
        span = own[-1].t - own[0].t
        assert 900 <= (len(own) - 1) / span <= 1100, (name, (len(own) - 1) / span)
        for point, pk in pcaps.items():  # every SYN inside the logged window, at every switch
            assert rc.flood_check(pk, ip, v_ip, start, stop, until=until).outside == 0, (name, point)
        sending = rc.flood_check(pcaps[f"s-{name}"], ip, v_ip, start, stop)  # the logged window is the sending
        assert 975 <= sending.pps <= 1025 and sending.inside >= len(own) - 1, (name, sending)
        fc = rc.flood_check(victim, ip, v_ip, start, stop)
        assert 900 <= fc.pps <= 1100, (ip, fc.pps)
    assert art.run_info.capture_drops == 0
    assert_nothing_left(art.run_info.prefix)


def test_collaborative_blackhole_plus_dos_in_one_run(tmp_path):
    ns = nodes(3)
    links = [link("uav0", "uav2"), link("uav2", "bs0"), link("uav1", "bs0")]
    p = make_plan(ns, links, [attack("blackhole", ["uav2"], "uav0", 3.0, 7.0, k=0),
                              attack("dos", ["uav1"], "uav0", 3.0, 7.0, k=1)], n_windows=3, window_s=4.0)
    art = realize(p, tmp_path / "r")
    assert art.exit_status == 0, art.exit_reason
    w = rc.windows(art.out_dir)
    (bs, be, _), (ds, de, drec) = w["blackhole-0"], w["dos-1"]
    bs0 = rc.read_pcap(art.out_dir / "pcap" / "s-bs0.pcap")
    victim_ip = drec["victim_ips"][0]
    fc = rc.flood_check(rc.read_pcap(art.out_dir / "pcap" / "s-uav1.pcap"), drec["attacker_ips"][0], victim_ip, ds, de,
                        until=rc.crossed(art.out_dir)["dos-1"])
    assert fc.outside == 0 and 850 <= fc.pps <= 1150
    from_victim = [x.t for x in bs0 if x.src == victim_ip]
    # blackholed at the victim's switch (stop is logged just after the table is gone: a few ms)
    assert not [t for t in from_victim if bs + 0.2 <= t < be - 0.05]
    assert [t for t in from_victim if t < bs] and [t for t in from_victim if t >= be]  # before and after
    http = [ln.split("\t") for ln in (art.out_dir / "logs" / "http-bs0-uav0.tsv").read_text().splitlines()]
    assert any(c == "200" and float(t) >= be for t, c, *_ in http)  # works after
    assert any(c != "200" and bs <= float(t) < be for t, c, *_ in http)  # fails inside
    assert_nothing_left(art.run_info.prefix)


# the CLI ---------------------------------------------------------------------------------------
def test_done_when_dos_run_via_cli(tmp_path):
    out = tmp_path / "r"
    t = time.monotonic()
    r = subprocess.run([UAVCAS, "run", "dos=1000-5-2-image-logdist-adaptive-random-30-95", "--seed", "1",
                        "--windows", "3", "--out", str(out)], capture_output=True, text=True, timeout=120)
    wall = time.monotonic() - t
    assert r.returncode == 0, r.stderr + r.stdout
    assert wall < 60
    info = json.loads((out / "run.json").read_text())
    assert info["exit_status"] == 0 and info["t0_unix"] and info["capture_drops"] == 0
    plan = json.loads((out / "plan.json").read_text())
    ips = {n["name"]: n["ip"] for n in plan["nodes"]}
    start, stop, rec = rc.windows(out)["dos-0"]
    attacker = rec["attackers"][0]
    pk = rc.read_pcap(out / "pcap" / f"s-{attacker}.pcap")
    fc = rc.flood_check(pk, rec["attacker_ips"][0], rec["victim_ips"][0], start, stop, until=rc.crossed(out)["dos-0"])
    assert fc.outside == 0 and 900 <= fc.pps <= 1100, fc.pps
    assert min(fc.per_second[1:-1]) >= 800  # steady, not bursty
    for k, u in enumerate(u for u in ips if u.startswith("uav")):
        bs_pk = rc.read_pcap(out / "pcap" / f"s-bs{k % 2}.pcap")
        conns, data = rc.http_transfers([x for x in bs_pk if x.src == ips[f"bs{k % 2}"] or x.dst == ips[f"bs{k % 2}"]],
                                        ips[u])
        assert conns >= 5 and data >= 100, (u, conns, data)
    shaping = [json.loads(x) for x in (out / "shaping.jsonl").read_text().splitlines()]
    assert len(shaping) == 2 * sum(len(w["links"]) for w in plan["windows"])
    assert_nothing_left(info["prefix"])


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


# how: "pid" signals the run alone; "ignored" starts it with SIGINT ignored, as a non-interactive
# shell starts background jobs (the run must still stop: this is how the test used to flake);
# "group" signals its whole process group, as Ctrl-C in a terminal does (the delay daemon, in a
# session of its own, must survive until the runner stops it).
@pytest.mark.parametrize("sig, code, how", [(signal.SIGINT, 130, "pid"), (signal.SIGINT, 130, "ignored"),
                                            (signal.SIGINT, 130, "group"), (signal.SIGTERM, 143, "pid")])
def test_interrupted_run_leaves_nothing(tmp_path, sig, code, how):
    out = tmp_path / "r"
    t = time.time()
    proc = subprocess.Popen([UAVCAS, "run", "replay=50,200,10,5,inc+dos=1000-4-1-image-logdist-adaptive-random-30-95",
                             "--windows", "3", "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True, preexec_fn=_ignore_sigint if how == "ignored" else None)
    prefix = rc.wait_registered(proc.pid, t)
    rc.wait_started(out)
    time.sleep(2)  # traffic flows through the delay stage
    (os.killpg if how == "group" else os.kill)(proc.pid, sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code, err
    info = json.loads((out / "run.json").read_text())
    assert info["exit_status"] == code and info["prefix"] == prefix
    assert info["wind_down_errors"] == [], info["wind_down_errors"]
    if info["shaper_backend"] == "htb-nft-nfqueue":  # the daemon answered at the end: it was alive
        assert info["delay_daemon"] and info["delay_daemon"]["packets"] > 0
    assert_nothing_left(prefix)


def test_kill_9_then_uavcas_clean_leaves_nothing(tmp_path):
    out = tmp_path / "r"
    t = time.time()
    proc = subprocess.Popen([UAVCAS, "run", "ddos=1000-4-1-image-logdist-adaptive-random-30-95", "--windows", "3",
                             "--out", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    prefix = rc.wait_registered(proc.pid, t)
    rc.wait_started(out)
    time.sleep(2)  # traffic flows through the delay stage
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(10)
    r = subprocess.run([UAVCAS, "clean", "--prefix", prefix], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    time.sleep(1.5)  # orphaned `timeout` wrappers exit once their tools are gone
    assert_nothing_left(prefix)
    # the killed run's directory: known as a run (its marker), but never extracted as complete
    assert json.loads((out / ".uavcas-run").read_text())["prefix"] == prefix and not (out / "run.json").exists()
    r = subprocess.run([UAVCAS, "extract", str(out), "--out", str(tmp_path / "ds")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and "never finished" in r.stderr and not (tmp_path / "ds").exists()


def test_benign_run_http(tmp_path):
    p = make_plan(nodes(2), [link("uav0", "bs0"), link("uav1", "uav0")], [], n_windows=2, window_s=3.0)
    art = realize(p, tmp_path / "r")
    assert art.exit_status == 0, art.exit_reason
    assert (art.out_dir / "attacks.jsonl").read_text() == ""
    info = art.run_info
    assert {c["uav"] for c in info.http_clients} == {"uav0", "uav1"}
    assert all(c["ok"] >= 3 and c["failed"] == 0 for c in info.http_clients)
    pk = rc.read_pcap(art.out_dir / "pcap" / "s-bs0.pcap")
    for u in ("uav0", "uav1"):
        assert not any(x.proto == 17 and x.dport == 14550 for x in pk)  # a plan without scenario: image only
        assert rc.http_transfers(pk, p.node(u).ip)[1] > 50


# the typed run directory -----------------------------------------------------------------------
def test_every_file_of_a_real_run_reads_through_the_typed_models(tmp_path):
    import shutil as sh

    from uavcas.events import AttackRate, AttackStart, AttackStop, Inject
    from uavcas.extract import extract
    from uavcas.rundir import RunDir, RunDirError
    from uavcas.twin.plan import plan as twin_plan

    # dos + replay: every record type (a blackhole on the shared victim would starve the replayer)
    p = twin_plan("dos=1000+replay=50,200,10,5,inc-4-1-image-logdist-adaptive-random-30-95", seed=2,
                  windows=2, window_s=4.0)
    art = realize(p, tmp_path / "r")
    assert art.exit_status == 0, art.exit_reason
    rd = RunDir(art.out_dir)
    assert rd.read_plan() == p and rd.read_plan().scenario.families == ("dos", "replay")
    info = rd.read_info()
    assert info == art.run_info and info.t0_unix and info.exit_status == 0
    lines = [ln for ln in rd.attacks_jsonl.read_text().splitlines() if ln.strip()]
    recs = rd.read_attacks()
    assert [r.to_line() for r in recs] == [ln + "\n" for ln in lines]  # every line, byte for byte
    assert {type(r) for r in recs} == {AttackStart, AttackStop, AttackRate, Inject}
    assert {r.family for r in recs if isinstance(r, AttackStart)} == {"dos", "replay"}
    assert len(rd.read_shaping()) == 2 * sum(len(w.links) for w in p.windows)
    shard = extract(rd.root)
    assert shard.info.n_flows > 0 and set(shard.frame["attacks"]) == {p.scenario.attacks_token}

    # an unknown or a missing field fails loudly, naming it
    bad = RunDir(tmp_path / "bad")
    sh.copytree(rd.root, bad.root)
    d = json.loads(rd.run_json.read_text())
    bad.run_json.write_text(json.dumps({**d, "colour": "red"}))
    with pytest.raises(RunDirError, match="unknown field 'colour'"):
        bad.read_info()
    bad.run_json.write_text(json.dumps({k: v for k, v in d.items() if k != "t0_unix"}))
    with pytest.raises(RunDirError, match="has no field 't0_unix'"):
        bad.read_info()
    first = json.loads(lines[0])
    bad.attacks_jsonl.write_text(json.dumps({**first, "colour": "red"}) + "\n")
    with pytest.raises(RunDirError, match=r"attacks.jsonl:1: unknown field 'colour'"):
        bad.read_attacks()
    bad.attacks_jsonl.write_text(json.dumps({k: v for k, v in first.items() if k != "t_unix"}) + "\n")
    with pytest.raises(RunDirError, match=r"attacks.jsonl:1: record has no 't_unix'"):
        bad.read_attacks()
    assert_nothing_left(info.prefix)
