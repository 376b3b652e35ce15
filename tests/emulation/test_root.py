"""Root integration tests on real namespaces (skipped with a reason without root).

Small scenarios (3-6 nodes), short measurements; a timing figure is measured a second time
before it fails, because other work shares the 2 cores.
"""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from uavcas.diagnostics import selftest
from uavcas.diagnostics.checks import HopConfig, loss_check
from uavcas.emulation import cleanup, kernel
from uavcas.emulation.emulation import Emulation
from uavcas.emulation.probe import CGROUP_ROOT
from uavcas.network.naming import Naming, new_prefix
from uavcas.testing.handmade_plans import link, nodes, plan, window

pytestmark = pytest.mark.root
REPO = Path(__file__).resolve().parents[2]
UAVCAS = str(REPO / ".venv" / "bin" / "uavcas")


def reachable(emu: Emulation, src: str, dst: str) -> bool:
    r = emu.run(src, ["ping", "-c", "1", "-W", "1", "-q", emu.ip(dst)], timeout_s=5)
    return r.returncode == 0


def reach_matrix(emu: Emulation, names: list[str]) -> dict[tuple[str, str], bool]:
    pairs = list(itertools.permutations(names, 2))
    with ThreadPoolExecutor(8) as ex:
        return dict(zip(pairs, ex.map(lambda p: reachable(emu, *p), pairs)))


def start_crashrun(prefix: str) -> tuple[subprocess.Popen, int]:
    """A run (crashrun.py) under `prefix`, set up and holding a child process; returns (run, child pid)."""
    proc = subprocess.Popen([sys.executable, str(Path(__file__).parent / "crashrun.py"), prefix],
                            stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline().split()
    if not (line and line[0] == "ready"):
        proc.kill()
        raise AssertionError(f"crashrun did not get ready: {line}")
    return proc, int(line[1])


# One measurement per check, never retried (a retry hides a real regression half the time):
# a correct shaper falls outside this binomial interval of the loss once in 10,000 runs.
LOSS_CONFIDENCE = 0.9999


def test_two_shaped_hops_accumulate_delay_and_loss():
    hops = [HopConfig(20, 3.0, 0.05), HopConfig(20, 5.0, 0.10)]
    p = plan(nodes(3), [window(0, [link("uav0", "uav1", 20, 3.0, 0.05), link("uav1", "uav2", 20, 5.0, 0.10)])])
    with Emulation(p, prefix=new_prefix()) as emu:
        rep = emu.apply_window(0)
        applied = {(r.src, r.dst): (r.applied_rate_mbps, r.applied_delay_ms, r.applied_loss) for r in rep.records}
        assert applied[("uav0", "uav1")] == (20.0, 3.0, 0.05) and applied[("uav2", "uav1")] == (20.0, 5.0, 0.10)

        r = selftest.measure_udp(emu, "uav0", "uav1", 1000, 1000)
        assert abs(r["delays_ms"]["median"] - 3.0) <= 1.0, r
        c = loss_check(r["loss"], 1000, hops[:1], LOSS_CONFIDENCE)
        assert c.ok, c

        r = selftest.measure_udp(emu, "uav0", "uav2", 2000, 1000)
        assert abs(r["delays_ms"]["median"] - 8.0) <= 1.0, r
        c = loss_check(r["loss"], 2000, hops, LOSS_CONFIDENCE)  # 1 - 0.95 * 0.90 = 14.5 %
        assert c.ok, c


def test_toggled_links_keep_planned_paths_and_no_others():
    names = ["uav0", "uav1", "uav2", "uav3", "bs0"]
    wins = [
        window(0, [link("uav0", "uav1"), link("uav1", "bs0"), link("uav2", "bs0"), link("uav3", "uav2")],
               routes=[["uav0", "uav1", "bs0"]]),
        window(1, [link("uav0", "bs0"), link("uav1", "uav2"), link("uav2", "bs0")],  # uav3 isolated
               routes=[["uav0", "bs0"]]),
        window(2, [link("uav0", "uav1"), link("uav1", "uav2"), link("uav2", "uav3"), link("uav3", "bs0"),
                   link("uav0", "bs0", delay_ms=10.0)],
               routes=[["uav0", "uav1", "uav2", "uav3", "bs0"]]),  # planned detour, not the direct link
    ]
    p = plan(nodes(4, 1), wins)
    with Emulation(p, prefix=new_prefix()) as emu:
        for w in range(3):
            emu.apply_window(w)
            active = {(lk.a, lk.b) for lk in wins[w].links}
            comp = _components(names, active)
            got = reach_matrix(emu, names)
            want = {(a, b): comp[a] == comp[b] for a, b in got}
            assert got == want, f"window {w}"
            for r in wins[w].routes:
                assert emu.forwarding.path(r.src, r.dst) == r.hops
        # window 2's route avoids the 10 ms direct link: RTT stays near zero
        rtt = _rtt_ms(emu, "uav0", "bs0")
        assert rtt < 5.0
        # wormhole: uav0 <-> bs0 forced through uav2 (window 0 topology has uav0-uav1-bs0-uav2)
        emu.apply_window(0)
        emu.set_wormholes([("uav0", "uav2", "bs0")])
        # uav2 hangs off bs0: no simple path uav0 -> uav2 -> bs0 exists; rejected, never looped
        assert emu.forwarding.rejected and emu.forwarding.path("uav0", "bs0") == ["uav0", "uav1", "bs0"]
        assert reachable(emu, "uav0", "bs0")


def test_wormhole_adds_the_attacker_hop_for_the_victim_only():
    # uav2 reaches bs0 through the victim's switch: its frames to bs0 must not follow the detour
    wins = [window(0, [link("uav0", "bs0", delay_ms=1.0), link("uav0", "uav1", delay_ms=4.0),
                       link("uav1", "bs0", delay_ms=4.0), link("uav2", "uav0")])]
    p = plan(nodes(3, 1), wins)
    with Emulation(p, prefix=new_prefix()) as emu:
        emu.apply_window(0)
        base, other = _rtt_ms(emu, "uav0", "bs0"), _rtt_ms(emu, "uav2", "bs0")
        emu.set_wormholes([("uav0", "uav1", "bs0")])
        assert emu.forwarding.detour_path("uav0", "bs0") == ["uav0", "uav1", "bs0"]
        worm, other_worm, back = _rtt_ms(emu, "uav0", "bs0"), _rtt_ms(emu, "uav2", "bs0"), _rtt_ms(emu, "bs0", "uav0")
        assert 1.5 < base < 4.0 and 15.0 < worm < 19.5 and 15.0 < back < 19.5, (base, worm, back)
        assert abs(other_worm - other) < 1.5, (other, other_worm)
        emu.set_wormholes([])
        assert _rtt_ms(emu, "uav0", "bs0") < 4.0
        port = emu.switch("uav1").link_ports["bs0"]
        assert port == "l1-3"


def test_two_prefixes_coexist_and_lazy_links():
    p = plan(nodes(3), [window(0, [link("uav0", "uav1"), link("uav1", "uav2")])])
    a, b = Emulation(p, prefix=new_prefix()), Emulation(p, prefix=new_prefix(), links="lazy")
    with a:
        a.apply_window(0)
        with b:
            assert b.switch("uav1").link_ports == {}
            rep = b.apply_window(0)
            assert rep.links_created == 2 and set(b.switch("uav1").link_ports) == {"uav0", "uav2"}
            assert reachable(a, "uav0", "uav2") and reachable(b, "uav0", "uav2")
        assert not any(ns.startswith(b.prefix) for ns in kernel.netns_list())
        assert reachable(a, "uav0", "uav2")  # b's teardown did not touch a


def test_cpu_cap_puts_node_processes_in_their_cgroup():
    p = plan(nodes(2), [window(0, [link("uav0", "uav1")])])
    with Emulation(p, prefix=new_prefix(), cpu_cap=0.5) as emu:
        proc = emu.popen("uav0", ["sleep", "5"])
        time.sleep(0.2)
        cg = Path(f"/proc/{proc.pid}/cgroup").read_text()
        assert f"uavcas.{emu.prefix}/uav0" in cg
        path = emu.hosts.caps.paths["uav0"]
        quota = (path / "cpu.max").read_text().split()[0] if emu.features.cgroup == "v2" else \
            (path / "cpu.cfs_quota_us").read_text().strip()
        assert quota == "50000"
    assert not path.exists()


def test_sigkill_then_clean_removes_exactly_that_run():
    prefix, bystander, decoy = new_prefix(), new_prefix(), new_prefix()
    kernel.run(["ip", "netns", "add", f"{decoy}-x"])  # not a uavcas run: no registry, no fabric
    other = Emulation(plan(nodes(2), [window(0, [link("uav0", "uav1")])]), prefix=bystander)
    with other:
        other.apply_window(0)
        proc, child = start_crashrun(prefix)
        try:
            naming = Naming(prefix)
            daemon_pids = kernel.netns_pids(naming.fabric_ns)
            assert daemon_pids and Path(f"/proc/{child}").exists()
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(5)
        finally:
            if proc.poll() is None:
                proc.kill()
        assert cleanup.is_live(bystander) and not cleanup.is_live(prefix)
        # plain `clean` skips the live bystander and removes the dead run
        r = subprocess.run([UAVCAS, "clean"], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        assert f"{bystander}: live run, skipped" in r.stdout
        left = [ns for ns in kernel.netns_list() if ns.startswith(prefix + "-")]
        assert left == []
        assert not Path(f"/proc/{child}").exists() or _zombie(child)
        assert all(not Path(f"/proc/{pid}").exists() or _zombie(pid) for pid in daemon_pids)
        assert not (CGROUP_ROOT / "cpu" / f"uavcas.{prefix}").exists()
        assert not naming.run_dir.exists()
        # the bystander run still works, and the unrelated namespace is untouched, even when named
        assert reachable(other, "uav0", "uav1")
        try:
            r = subprocess.run([UAVCAS, "clean", "--prefix", decoy], capture_output=True, text=True, timeout=60)
            assert r.returncode == 0 and "removed 0 namespaces" in r.stdout
            assert f"{decoy}-x" in kernel.netns_list()
        finally:
            kernel.run(["ip", "netns", "del", f"{decoy}-x"], check=False)
        r = subprocess.run([UAVCAS, "clean", "--prefix", prefix], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0 and "removed 0 namespaces" in r.stdout


def test_delay_daemon_has_its_own_session_and_its_death_fails_the_next_window():
    p = plan(nodes(2), [window(0, [link("uav0", "uav1", 10, 2, 0.0)])])
    with Emulation(p, prefix=new_prefix()) as emu:
        if emu.backend != "htb-nft-nfqueue":
            pytest.skip(f"shaper {emu.backend} has no delay daemon")
        emu.apply_window(0)
        daemon = emu.shaper.daemon
        assert os.getsid(daemon.pid) == daemon.pid != os.getsid(0)  # a group Ctrl-C does not reach it
        os.kill(daemon.pid, signal.SIGKILL)
        daemon.wait(5)
        with pytest.raises(kernel.KernelError, match="delay daemon died .killed by signal 9"):
            emu.apply_window(0)


def test_not_root_style_errors_are_one_line():
    r = subprocess.run([UAVCAS, "clean", "--prefix", "BAD"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and r.stderr.count("\n") == 1


def _zombie(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


def _components(names, links):
    comp = {n: n for n in names}

    def find(x):
        while comp[x] != x:
            x = comp[x]
        return x

    for a, b in links:
        comp[find(a)] = find(b)
    return {n: find(n) for n in names}


def _rtt_ms(emu: Emulation, src: str, dst: str) -> float:
    r = emu.run(src, ["ping", "-c", "5", "-i", "0.05", "-q", emu.ip(dst)], timeout_s=10)
    assert r.returncode == 0, r.stdout
    return float(r.stdout.split("=")[-1].split("/")[1])


def test_sigterm_tears_down_without_clean():
    prefix = new_prefix()
    proc, child = start_crashrun(prefix)
    try:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(15) != 0
    finally:
        if proc.poll() is None:
            proc.kill()
    assert not [ns for ns in kernel.netns_list() if ns.startswith(prefix + "-")]
    assert not Path(f"/proc/{child}").exists() or _zombie(child)
    assert not Naming(prefix).run_dir.exists() and not cleanup.is_live(prefix)


def test_hooks_blackhole_table_and_mirror():
    p = plan(nodes(3), [window(0, [link("uav0", "uav1"), link("uav1", "uav2")])])
    with Emulation(p, prefix=new_prefix()) as emu:
        emu.apply_window(0)
        sw = emu.switch("uav1")
        ports = ", ".join(f'"{x}"' for x in sw.all_ports)
        victim = emu.ip("uav2")
        emu.fabric.nft(f"table bridge bh {{\n chain fw {{\n  type filter hook forward priority 0; policy accept;\n"
                       f"  iifname {{ {ports} }} ether type ip ip daddr {victim} drop\n }}\n}}\n")
        assert not reachable(emu, "uav0", "uav2") and reachable(emu, "uav0", "uav1")
        emu.fabric.nft_delete_table("bh")
        assert reachable(emu, "uav0", "uav2")
        emu.fabric.mirror(sw.link_ports["uav0"], sw.host_port)  # transit frames now reach uav1's eth0
        cap = emu.popen("uav1", ["tcpdump", "-c", "3", "-n", "-i", "eth0", "icmp and dst", victim],
                        timeout_s=10, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        time.sleep(0.5)
        emu.run("uav0", ["ping", "-c", "5", "-i", "0.1", "-q", victim], timeout_s=5)
        out, _ = cap.communicate(timeout=10)
        assert out.count("ICMP echo request") == 3
        emu.fabric.unmirror(sw.link_ports["uav0"])


def test_a_dead_link_drops_everything_and_reads_back_as_loss_one():
    # The channel gives loss 1.0 to links far out of range (e.g. 3GPP NLOS at 10 dBm).
    p = plan(nodes(3), [window(0, [link("uav0", "uav1", 20, 1.0, 1.0), link("uav1", "uav2", 20, 1.0, 0.0)])])
    with Emulation(p, prefix=new_prefix()) as emu:
        rep = emu.apply_window(0)
        applied = {(r.src, r.dst): r.applied_loss for r in rep.records}
        assert applied[("uav0", "uav1")] == 1.0 and applied[("uav1", "uav0")] == 1.0
        assert applied[("uav1", "uav2")] == 0.0
        assert not reachable(emu, "uav0", "uav1") and reachable(emu, "uav1", "uav2")


def test_flood_rate_holds_on_a_saturated_machine(tmp_path):
    """Paced from outside, a flood keeps its nominal rate when every core is busy (the old
    interval correction ran away to 2,500 pps when the schedule was late)."""
    from uavcas.attacks.tools import flood

    p = plan(nodes(3), [window(0, [link("uav0", "uav1"), link("uav1", "uav2")])])
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2 * os.cpu_count() + 1)]
    try:
        with Emulation(p, prefix=new_prefix()) as emu:
            emu.apply_window(0)
            f = flood.Flood(emu, "dos-0", "uav0", emu.ip("uav2"), 1000.0, tmp_path, 60)
            for proc in f.prepare():
                emu._procs.append(proc.popen)
            assert f.counters() == {"syn": 0, "gated": 1}  # hping3's own first SYN never left
            flood.start_all([f])
            time.sleep(3.0)
            flood.close_all([f])
            (res,) = flood.collect_all([f])
    finally:
        for h in hogs:
            h.kill()
            h.wait()
    assert res.syn_count == res.signals  # one SYN per signal, none merged
    assert 900 <= res.measured_pps <= 1100, res
