"""The packet table's `mav_msgid` column on a built capture: real pymavlink frames in a scapy pcap."""

from __future__ import annotations

import pytest
from scapy.layers.inet import IP, TCP, UDP
from scapy.layers.l2 import Ether
from scapy.packet import Raw
from scapy.utils import wrpcap

from uavcas.flows import read_packets
from uavcas.flows.packets import NO_MAVLINK, table_from_rows


def _mav(version: int, sysid: int = 1):
    if version == 1:
        from pymavlink.dialects.v10 import common
    else:
        from pymavlink.dialects.v20 import common
    return common, common.MAVLink(None, srcSystem=sysid, srcComponent=1)


def _frames() -> list[tuple[str, bytes, int]]:
    """(what, UDP payload, expected mav_msgid)."""
    m2, mav2 = _mav(2)
    gpi = mav2.global_position_int_encode(3000, 357274510, -786959740, 80000, 80000, 120, -50, 7, 9000).pack(mav2)
    raw = mav2.gps_raw_int_encode(3_000_000, 3, 357274510, -786959740, 80000, 100, 100, 130, 9000, 12).pack(mav2)
    hb = mav2.heartbeat_encode(2, 3, 0, 3, 4, 3).pack(mav2)
    m1, mav1 = _mav(1)
    v1 = mav1.attitude_encode(1000, 0.1, 0.2, 0.3, 0, 0, 0).pack(mav1)
    ms, signer = _mav(2, sysid=7)
    signer.signing.secret_key = bytes(range(32))
    signer.signing.sign_outgoing = True
    signed = signer.command_long_encode(1, 1, 20, 0, 0, 0, 0, 0, 0, 0, 0).pack(signer)
    assert signed[2] & 0x01 and len(signed) == 10 + signed[1] + 2 + 13  # a signed MAVLink 2 frame
    return [
        ("GLOBAL_POSITION_INT", gpi, m2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT),  # 33
        ("GPS_RAW_INT", raw, m2.MAVLINK_MSG_ID_GPS_RAW_INT),  # 24
        ("HEARTBEAT", hb, 0),  # id 0 is a message: the absent value is -1
        ("two frames in one datagram", gpi + hb, 33),  # the first one's id
        ("MAVLink 1 ATTITUDE", v1, m1.MAVLINK_MSG_ID_ATTITUDE),  # 30
        ("signed COMMAND_LONG", signed, m2.MAVLINK_MSG_ID_COMMAND_LONG),  # 76
        ("frame longer than its datagram", gpi[:-5], NO_MAVLINK),
        ("unknown incompat flag", bytes([gpi[0], gpi[1], 0x02]) + gpi[3:], NO_MAVLINK),
        ("RTP video", bytes([0x80, 0x60]) + bytes(30), NO_MAVLINK),
        ("0xFD and nothing else", b"\xfd", NO_MAVLINK),
    ]


@pytest.fixture(scope="module")
def capture(tmp_path_factory):
    path = tmp_path_factory.mktemp("mav") / "s-uav0.pcap"
    frames = _frames()
    pkts = []
    for k, (_, payload, _) in enumerate(frames):
        p = Ether() / IP(src="10.9.0.1", dst="10.9.0.10", id=k) / UDP(sport=40000, dport=14550) / Raw(payload)
        p.time = 1_700_000_000 + k * 0.01
        pkts.append(p)
    tcp = (Ether() / IP(src="10.9.0.1", dst="10.9.0.10", id=99) / TCP(sport=5000, dport=80, flags="PA")
           / Raw(frames[0][1]))
    tcp.time = 1_700_000_001
    pkts.append(tcp)  # a MAVLink frame in a TCP segment: not a UDP datagram, not decoded
    wrpcap(str(path), pkts)
    return path, [f[2] for f in frames] + [NO_MAVLINK]


def test_msgid_of_each_datagram(capture):
    path, expected = capture
    t = read_packets([path])
    assert t["mav_msgid"].dtype.name == "int32"
    assert t["mav_msgid"].tolist() == expected


def test_msgid_needs_the_frame_header_captured(tmp_path):
    """A snap length that cuts a MAVLink 2 header leaves the id unknown (-1), not garbage."""
    _, payload, _ = _frames()[0]
    p = Ether() / IP(src="10.9.0.1", dst="10.9.0.10") / UDP(sport=40000, dport=14550) / Raw(payload)
    p.time = 1_700_000_000
    full, cut = tmp_path / "full.pcap", tmp_path / "cut.pcap"
    wrpcap(str(full), [p])
    short = Ether(bytes(p)[:14 + 20 + 8 + 8])  # 8 of the 10 header bytes captured
    short.time, short.wirelen = p.time, len(bytes(p))
    wrpcap(str(cut), [short], snaplen=14 + 20 + 8 + 8)
    assert read_packets([full])["mav_msgid"].tolist() == [33]
    assert read_packets([cut])["mav_msgid"].tolist() == [NO_MAVLINK]


def test_hand_built_rows_default_to_no_mavlink():
    t = table_from_rows([{"ts_ns": 1, "proto": 17}, {"ts_ns": 2, "proto": 17, "mav_msgid": 0}], ["p"])
    assert t["mav_msgid"].tolist() == [NO_MAVLINK, 0]
