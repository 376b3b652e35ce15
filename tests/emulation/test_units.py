"""Emulation pieces that need no root: exact shaper requests, host config, the run registry."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from uavcas.emulation import cleanup
from uavcas.emulation.hosts import HostSpec, host_lines, node_argv, subnet_prefixlen
from uavcas.emulation.nfqdelay import request_line, verdict_msg
from uavcas.emulation.readback import parse_tc_rate, parse_tc_size
from uavcas.emulation.shaping import (
    FallbackShaper,
    NetemShaper,
    Shape,
    nft_loss_lines,
    nft_port_init_lines,
    nft_table_ruleset,
)
from uavcas.network import naming


# shaping requests ---------------------------------------------------------------------------------
def _shape(port="l0-1", rate=10.0, delay=5.0, loss=0.01):
    return Shape("uav0", "uav1", port, rate, delay, loss)


def test_netem_shaper_exact_requests(tmp_path: Path):
    sh = NetemShaper("x-fab", tmp_path)
    assert sh.init_lines(["l0-1"]) == [
        "qdisc add dev l0-1 root handle 1: htb default 1",
        "class add dev l0-1 parent 1: classid 1:1 htb rate 1000000000bit ceil 1000000000bit quantum 1514",
        "qdisc add dev l0-1 parent 1:1 handle 10: netem delay 0us loss 0% limit 2000"]
    assert sh.change_lines([_shape()]) == [
        "class change dev l0-1 parent 1: classid 1:1 htb rate 10000000bit ceil 10000000bit quantum 1514",
        "qdisc change dev l0-1 parent 1:1 handle 10: netem delay 5000us loss 1% limit 47"]
    sh.current["l0-1"] = _shape()
    assert sh.change_lines([_shape()]) == []  # unchanged: no request at all
    assert sh.change_lines([_shape(delay=2.5, loss=0.125)]) == [
        "qdisc change dev l0-1 parent 1:1 handle 10: netem delay 2500us loss 12.5% limit 45"]


def test_fallback_window_change_is_one_daemon_request_and_no_tc(tmp_path: Path):
    sh = FallbackShaper("x-fab", tmp_path)
    # the HTB class + pfifo a port is created with only count: never changed afterwards
    assert sh.init_lines(["l1-0"])[-1] == "qdisc add dev l1-0 parent 1:1 handle 10: pfifo limit 2000"
    req = sh.daemon_request([_shape()])
    assert request_line(req) == "set l0-1=5000,10000000,1600,42"  # delay us, rate bit/s, bucket B, queue limit
    sh.current["l0-1"] = _shape()
    assert sh.daemon_request([_shape()]) is None  # unchanged: no request at all
    assert request_line(sh.daemon_request([_shape(delay=1.0)])) == "set l0-1=1000,10000000,1600,42"


def test_tc_sizes_are_read_back_in_bytes():
    # `tc class show` prints the HTB burst in bytes or binary multiples (shaping.jsonl applied_burst_b)
    assert [parse_tc_size(x) for x in ("1599b", "11244b", "73Kb", "3Mb")] == [1599, 11244, 73 * 1024, 3 * 1024**2]


def test_nft_loss_rewrites_only_the_given_port_chains():
    table = nft_table_ruleset()
    assert "oifname vmap @ports" in table and "type filter hook forward" in table
    assert nft_port_init_lines(["l0-1", "l1-0"]) == [
        "add chain bridge uavcas_shape p_l0_1", "add chain bridge uavcas_shape p_l1_0",
        "add counter bridge uavcas_shape c_l0_1", "add counter bridge uavcas_shape c_l1_0",
        'add element bridge uavcas_shape ports { "l0-1" : jump p_l0_1, "l1-0" : jump p_l1_0 }']
    assert nft_loss_lines({"l0-1": 0.05, "l1-0": 0.0, "l3-1": 1.0}) == [
        "flush chain bridge uavcas_shape p_l0_1",
        "add rule bridge uavcas_shape p_l0_1 numgen random mod 1000000 < 50000 counter name c_l0_1 drop",
        "flush chain bridge uavcas_shape p_l1_0",
        "flush chain bridge uavcas_shape p_l3_1",
        "add rule bridge uavcas_shape p_l3_1 counter name c_l3_1 drop"]


def test_tc_rate_parsing():
    assert parse_tc_rate("9600Kbit") == pytest.approx(9.6)
    assert parse_tc_rate("54Mbit") == 54 and parse_tc_rate("800bit") == pytest.approx(0.0008)


# hosts ---------------------------------------------------------------------------------------------
def test_host_lines_static_arp_and_subnet():
    specs = [HostSpec(f"uav{i}", i, f"10.77.0.{i + 1}", f"02:00:00:00:00:{i:02x}", f"p-uav{i}") for i in range(3)]
    assert subnet_prefixlen([s.ip for s in specs]) == 24
    assert subnet_prefixlen(["10.77.0.1", "10.77.1.1"]) == 23
    lines = host_lines(specs[0], specs, 24)
    assert lines[0] == "link set lo up" and lines[-1] == "link set eth0 up"
    assert "neigh replace 10.77.0.2 lladdr 02:00:00:00:00:01 dev eth0 nud permanent" in lines
    assert not any("10.77.0.1 " in ln for ln in lines if ln.startswith("neigh"))


def test_node_argv_joins_cgroup_before_netns():
    argv = node_argv("p-uav0", ["sleep", "1"], Path("/cg/uav0/cgroup.procs"), timeout_s=5)
    assert argv[:4] == ["sh", "-c", 'echo $$ > "$0" && exec "$@"', "/cg/uav0/cgroup.procs"]
    assert argv[4:] == ["timeout", "-k", "1", "5", "ip", "netns", "exec", "p-uav0", "sleep", "1"]


# nfqueue wire format and statistics ------------------------------------------------------------------
def test_verdict_message_layout():
    msg = verdict_msg(3, 0x01020304)
    length, kind, flags = struct.unpack_from("=IHH", msg)
    assert length == len(msg) == 32 and kind == 0x301 and flags == 1
    assert msg[18:20] == b"\x00\x03"  # res_id is the queue number, big-endian
    assert msg[-8:] == struct.pack("!II", 1, 0x01020304)  # NF_ACCEPT, packet id


# registry --------------------------------------------------------------------------------------------
def test_registry_lock_marks_live(tmp_path, monkeypatch):
    monkeypatch.setattr(naming, "RUN_ROOT", tmp_path)
    monkeypatch.setattr(cleanup, "RUN_ROOT", tmp_path)
    lock = cleanup.RunLock(cleanup.RunRecord("uczz01", 1, ["uczz01-fab"]))
    assert cleanup.is_live("uczz01") and cleanup.registered_prefixes() == ["uczz01"]
    with pytest.raises(RuntimeError):
        cleanup.RunLock(cleanup.RunRecord("uczz01", 1, []))
    lock.release()
    assert not cleanup.is_live("uczz01") and cleanup.registered_prefixes() == []
