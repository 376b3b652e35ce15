"""Unit tests of the emulation's own apps (no root): the capture. (The benign apps' are in
tests/traffic, the attack tools' in tests/attacks/tools.)"""

from __future__ import annotations

from uavcas.emulation.apps import capture


def test_capture_stats_parse():
    err = ("tcpdump: listening on s0\n1234 packets captured\n1240 packets received by filter\n"
           "6 packets dropped by kernel\n")
    assert capture.parse_stats(err) == {"captured": 1234, "received by filter": 1240, "dropped by kernel": 6}
    argv = capture.argv("s3", capture.Path("/x/s-uav3.pcap"))
    assert "-p" not in argv and "-U" in argv and argv[argv.index("-Z") + 1] == "root"
    assert capture.point_name("uav3") == "s-uav3"
