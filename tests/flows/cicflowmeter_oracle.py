"""An independent oracle for the `cic` termination policy and the 47 `cic` features.

A deliberately literal, per-packet, plain-Python re-statement of CICFlowMeter-4.0
(github.com/ahlashkari/CICFlowMeter, package cic.cs.unb.ca.jnetpcap):
- `read_packets`: PacketReader.getIpv4Info (what a packet carries into the flow generator),
- `FlowGenerator.add_packet`: FlowGenerator.addPacket (where flows start and end),
- `BasicFlow`: BasicFlow.firstPacket / addPacket / updateActiveIdleTime / detectUpdateSubflows and
  the getters behind the 47 columns of `uavcas.flows.standards.cic.FEATURES`,
- `SummaryStatistics`: Apache commons-math3 SummaryStatistics (mean, sample variance).
It shares no code with `uavcas.flows` on purpose; it is slow and meant for small captures.

Where uavcas documents a deliberate difference from CICFlowMeter, this oracle follows
CICFlowMeter and the TEST restricts the comparison to what both define:
- CICFlowMeter gives every IPv4 packet that is neither TCP nor UDP protocol 0 and ports 0 (ICMP
  and the rest share one flow per address pair); uavcas keeps the protocol. Such packets are read
  here as CICFlowMeter reads them (protocol 0) and only TCP/UDP flows are compared.
- Later IP fragments: CICFlowMeter cannot find their transport header (protocol 0, so outside
  the compared flows); uavcas adds them to their datagram's flow. Flows of a 5-tuple that had
  fragments are flagged (`Flow.fragmented`) and not compared.
- IPv6: CICFlowMeter's command line reads IPv4 only (Cmd.readPcapFile: readIP6 = false) and its
  IPv6 path keeps milliseconds and no flags; uavcas reads IPv6 like IPv4. With `ipv6=True` this
  oracle reads IPv6 TCP/UDP (no extension headers) with the IPv4 rules, uavcas's reading.
- Direction: CICFlowMeter compares source ADDRESSES only (Arrays.equals(flow.getSrc(),
  packet.getSrc())), uavcas the endpoint (address and port); they differ only for a host talking
  to itself. `direction_by_port=True` gives uavcas's rule; the test uses it only for flows whose
  two addresses are equal and checks the rest with the literal rule.
"""

from __future__ import annotations

import ipaddress
import math
from dataclasses import dataclass, field
from pathlib import Path

import dpkt
import numpy as np

FLOW_TIMEOUT_US = 120_000_000  # Cmd.readPcapFile: flowTimeout = 120000000L
ACTIVITY_TIMEOUT_US = 5_000_000  # Cmd.readPcapFile: activityTimeout = 5000000L

# TCP flag bits (BasicPacketInfo's flagFIN ... flagCWR, set from jnetpcap's Tcp.flags_*)
FIN, SYN, RST, PSH, ACK, URG, ECE, CWR = 0x01, 0x02, 0x04, 0x08, 0x10, 0x20, 0x40, 0x80


# --------------------------------------------------------------------------------------------
# commons-math3 SummaryStatistics
# --------------------------------------------------------------------------------------------


class SummaryStatistics:
    """org.apache.commons.math3.stat.descriptive.SummaryStatistics, for the values used here:
    getN, getSum, getMin, getMax, getMean (FirstMoment), getVariance (SecondMoment / (n - 1),
    0 for one value), getStandardDeviation (0 for one value). Empty: NaN except N and sum (0)."""

    def __init__(self) -> None:
        self.n = 0
        self.sum = 0.0
        self.min = math.nan
        self.max = math.nan
        self.m1 = math.nan  # FirstMoment
        self.m2 = math.nan  # SecondMoment

    def add_value(self, value: float) -> None:
        value = float(value)
        if self.n == 0:
            self.m1, self.m2 = 0.0, 0.0
            self.min, self.max = value, value
        else:
            self.min, self.max = min(self.min, value), max(self.max, value)
        self.n += 1
        self.sum += value
        dev = value - self.m1  # FirstMoment.increment
        n_dev = dev / self.n
        self.m1 += n_dev
        self.m2 += (self.n - 1) * dev * n_dev  # SecondMoment.increment

    def get_mean(self) -> float:
        return self.m1 if self.n > 0 else math.nan

    def get_variance(self) -> float:
        if self.n == 0:
            return math.nan
        if self.n == 1:
            return 0.0
        return self.m2 / (self.n - 1)  # Variance, isBiasCorrected = true

    def get_standard_deviation(self) -> float:
        if self.n == 0:
            return math.nan
        return math.sqrt(self.get_variance()) if self.n > 1 else 0.0


def java_divide(a: float, b: float) -> float:
    """Java's double division: x / 0.0 is +-Infinity, 0.0 / 0.0 is NaN (IEEE 754, as numpy)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.float64(a) / np.float64(b))


# --------------------------------------------------------------------------------------------
# PacketReader: capture -> BasicPacketInfo
# --------------------------------------------------------------------------------------------


@dataclass
class PacketInfo:
    """BasicPacketInfo: what FlowGenerator and BasicFlow use of one packet."""

    src: bytes
    dst: bytes
    src_port: int
    dst_port: int
    protocol: int  # 6, 17, or 0 for anything else (PacketReader sets only these two)
    timestamp: int  # whole microseconds (jnetpcap timestampInMicros)
    payload_bytes: int
    header_bytes: int
    flags: int  # TCP flags byte, 0 for UDP and others
    fragment: bool = False  # an IP fragment (see the module docstring)

    def fwd_flow_id(self) -> tuple:  # BasicPacketInfo.fwdFlowId
        return (self.src, self.dst, self.src_port, self.dst_port, self.protocol)

    def bwd_flow_id(self) -> tuple:  # BasicPacketInfo.bwdFlowId
        return (self.dst, self.src, self.dst_port, self.src_port, self.protocol)

    def has(self, bit: int) -> bool:
        return bool(self.flags & bit)


def _records(path: Path):
    """(linktype, [(timestamp_us, frame bytes)]) of a pcap or pcapng capture, read with scapy's
    reader, whose record times are exact decimals (a float is too coarse for whole microseconds
    at today's epoch). Sub-microsecond resolutions are truncated, as libpcap does when jnetpcap
    opens a capture at its default (microsecond) precision."""
    from scapy.utils import PcapReader

    with PcapReader(str(path)) as reader:
        out = [(int(pkt.time * 1_000_000), bytes(pkt)) for pkt in reader]
        # pcapng: the link type of the (single) interface described in the file
        linktype = reader.linktype if hasattr(reader, "linktype") else reader.interfaces[0][0]
        return linktype, out


def _network_layer(linktype: int, frame: bytes):
    """The IP packet inside a frame (Ethernet incl. VLAN, Linux SLL, raw IP), or None."""
    if linktype == dpkt.pcap.DLT_EN10MB:
        ip = dpkt.ethernet.Ethernet(frame).data
    elif linktype == dpkt.pcap.DLT_LINUX_SLL:
        ip = dpkt.sll.SLL(frame).data
    elif linktype in (dpkt.pcap.DLT_RAW, 12, 14):  # LINKTYPE_RAW and the two old DLT_RAW values
        ip = dpkt.ip.IP(frame) if frame[0] >> 4 == 4 else dpkt.ip6.IP6(frame)
    else:
        raise ValueError(f"link type {linktype} not handled by the oracle")
    return ip if isinstance(ip, (dpkt.ip.IP, dpkt.ip6.IP6)) else None


def _transport(segment, l4_len: int):
    """(src_port, dst_port, protocol, payload, header, flags) as PacketReader.getIpv4Info sets
    them: TCP header = data offset * 4, UDP header = 8, payload = the rest of the IP payload as
    the IP length fields give it (so Ethernet padding is not payload); others: protocol 0, no
    ports (only TCP and UDP set them)."""
    if isinstance(segment, dpkt.tcp.TCP):
        header = segment.off * 4
        return segment.sport, segment.dport, 6, max(l4_len - header, 0), header, segment.flags & 0xFF
    if isinstance(segment, dpkt.udp.UDP):
        return segment.sport, segment.dport, 17, max(l4_len - 8, 0), 8, 0
    return 0, 0, 0, 0, 0, 0


def read_packets(path: Path, ipv6: bool = False) -> list[PacketInfo]:
    """PacketReader.nextPacket for every record, in file order (FlowGenerator sees them so)."""
    linktype, records = _records(Path(path))
    out = []
    for ts_us, frame in records:
        ip = _network_layer(linktype, frame)
        if isinstance(ip, dpkt.ip.IP):
            fragment = bool(ip.mf) or ip.offset > 0
            if ip.offset > 0:  # a later fragment: no transport header to find (protocol 0)
                fields = (0, 0, 0, 0, 0, 0)
            else:
                fields = _transport(ip.data, ip.len - ip.hl * 4)
            out.append(PacketInfo(ip.src, ip.dst, *fields[:3], ts_us, *fields[3:], fragment=fragment))
        elif isinstance(ip, dpkt.ip6.IP6) and ipv6 and ip.nxt in (6, 17):
            fields = _transport(ip.data, ip.plen)  # no extension headers (ip.nxt is TCP or UDP)
            out.append(PacketInfo(ip.src, ip.dst, *fields[:3], ts_us, *fields[3:]))
        # anything else (ARP, IPv6 by default): PacketReader returns null, addPacket never sees it
    return out


# --------------------------------------------------------------------------------------------
# BasicFlow
# --------------------------------------------------------------------------------------------


@dataclass
class BasicFlow:
    """BasicFlow, bidirectional, with the state behind the 47 features."""

    packet: PacketInfo
    activity_timeout: int
    direction_by_port: bool = False
    flow_src: tuple | None = None  # (src, dst, src_port, dst_port) of the constructor with 7 args
    fwd_pkt_stats: SummaryStatistics = field(default_factory=SummaryStatistics)
    bwd_pkt_stats: SummaryStatistics = field(default_factory=SummaryStatistics)
    flow_iat: SummaryStatistics = field(default_factory=SummaryStatistics)
    forward_iat: SummaryStatistics = field(default_factory=SummaryStatistics)
    backward_iat: SummaryStatistics = field(default_factory=SummaryStatistics)
    flow_length_stats: SummaryStatistics = field(default_factory=SummaryStatistics)
    flow_active: SummaryStatistics = field(default_factory=SummaryStatistics)
    flow_idle: SummaryStatistics = field(default_factory=SummaryStatistics)
    flag_counts: dict = field(default_factory=lambda: dict.fromkeys(("FIN", "SYN", "RST", "PSH", "ACK", "URG", "CWR",
                                                                     "ECE"), 0))
    forward: list = field(default_factory=list)
    backward: list = field(default_factory=list)
    forward_bytes: int = 0
    backward_bytes: int = 0
    f_header_bytes: int = 0
    b_header_bytes: int = 0
    f_fin_cnt: int = 0
    b_fin_cnt: int = 0
    src: bytes | None = None  # initParameters: src = dst = null
    dst: bytes | None = None
    src_port: int = 0
    dst_port: int = 0
    protocol: int = 0
    flow_start_time: int = 0
    flow_last_seen: int = 0
    forward_last_seen: int = 0
    backward_last_seen: int = 0
    start_active_time: int = 0
    end_active_time: int = 0
    sf_last_packet_ts: int = -1  # detectUpdateSubflows' state
    fragmented: bool = False  # oracle bookkeeping only (module docstring)

    def __post_init__(self) -> None:
        # BasicFlow(isBidirectional, packet, flowSrc, flowDst, flowSrcPort, flowDstPort, activityTimeout):
        # firstPacket(packet) runs while src is still null, so the first packet is forward, and
        # only then are src/dst/ports set to the given (older flow's) orientation.
        self.first_packet(self.packet)
        if self.flow_src is not None:
            self.src, self.dst, self.src_port, self.dst_port = self.flow_src

    def is_forward(self, packet: PacketInfo) -> bool:
        """Arrays.equals(this.src, packet.getSrc()) (plus the port with direction_by_port)."""
        same = self.src == packet.src
        if self.direction_by_port:
            same = same and self.src_port == packet.src_port
        return same

    def first_packet(self, packet: PacketInfo) -> None:  # BasicFlow.firstPacket
        self.fragmented |= packet.fragment
        self.detect_update_subflows(packet)
        self.check_flags(packet)
        self.flow_start_time = packet.timestamp
        self.flow_last_seen = packet.timestamp
        self.start_active_time = packet.timestamp
        self.end_active_time = packet.timestamp
        self.flow_length_stats.add_value(packet.payload_bytes)  # once here ...
        if self.src is None:
            self.src, self.src_port = packet.src, packet.src_port
        if self.dst is None:
            self.dst, self.dst_port = packet.dst, packet.dst_port
        if self.is_forward(packet):
            self.flow_length_stats.add_value(packet.payload_bytes)  # ... and once more
            self.fwd_pkt_stats.add_value(packet.payload_bytes)
            self.f_header_bytes = packet.header_bytes
            self.forward_last_seen = packet.timestamp
            self.forward_bytes += packet.payload_bytes
            self.forward.append(packet)
        else:  # unreachable (src was just set from this packet), kept for literalness
            self.flow_length_stats.add_value(packet.payload_bytes)
            self.bwd_pkt_stats.add_value(packet.payload_bytes)
            self.b_header_bytes = packet.header_bytes
            self.backward_last_seen = packet.timestamp
            self.backward_bytes += packet.payload_bytes
            self.backward.append(packet)
        self.protocol = packet.protocol

    def add_packet(self, packet: PacketInfo) -> None:  # BasicFlow.addPacket (isBidirectional)
        self.fragmented |= packet.fragment
        self.detect_update_subflows(packet)
        self.check_flags(packet)
        now = packet.timestamp
        self.flow_length_stats.add_value(packet.payload_bytes)
        if self.is_forward(packet):
            self.fwd_pkt_stats.add_value(packet.payload_bytes)
            self.f_header_bytes += packet.header_bytes
            self.forward.append(packet)
            self.forward_bytes += packet.payload_bytes
            if len(self.forward) > 1:
                self.forward_iat.add_value(now - self.forward_last_seen)
            self.forward_last_seen = now
        else:
            self.bwd_pkt_stats.add_value(packet.payload_bytes)
            self.b_header_bytes += packet.header_bytes
            self.backward.append(packet)
            self.backward_bytes += packet.payload_bytes
            if len(self.backward) > 1:
                self.backward_iat.add_value(now - self.backward_last_seen)
            self.backward_last_seen = now
        self.flow_iat.add_value(packet.timestamp - self.flow_last_seen)
        self.flow_last_seen = packet.timestamp

    def check_flags(self, packet: PacketInfo) -> None:  # BasicFlow.checkFlags
        for name, bit in (("FIN", FIN), ("SYN", SYN), ("RST", RST), ("PSH", PSH),
                          ("ACK", ACK), ("URG", URG), ("CWR", CWR), ("ECE", ECE)):  # fmt: skip
            if packet.has(bit):
                self.flag_counts[name] += 1

    def detect_update_subflows(self, packet: PacketInfo) -> None:
        """BasicFlow.detectUpdateSubflows: only its call of updateActiveIdleTime matters for the
        47 features (a gap of more than 1 s since the previous packet of the flow)."""
        if self.sf_last_packet_ts == -1:
            self.sf_last_packet_ts = packet.timestamp
        if (packet.timestamp - self.sf_last_packet_ts) / 1_000_000.0 > 1.0:
            self.update_active_idle_time(packet.timestamp, self.activity_timeout)
        self.sf_last_packet_ts = packet.timestamp

    def update_active_idle_time(self, current_time: int, threshold: int) -> None:  # BasicFlow.updateActiveIdleTime
        if current_time - self.end_active_time > threshold:
            if self.end_active_time - self.start_active_time > 0:
                self.flow_active.add_value(self.end_active_time - self.start_active_time)
            self.flow_idle.add_value(current_time - self.end_active_time)
            self.start_active_time = current_time
            self.end_active_time = current_time
        else:
            self.end_active_time = current_time

    def packet_count(self) -> int:  # BasicFlow.packetCount (bidirectional)
        return len(self.forward) + len(self.backward)

    def features(self) -> dict[str, float]:
        """The 47 columns of uavcas.flows.standards.cic.FEATURES from BasicFlow's getters (dumpFlowBasedFeaturesEx)."""
        duration = self.flow_last_seen - self.flow_start_time  # getFlowDuration
        any_pkt = len(self.forward) > 0 or len(self.backward) > 0
        fwd2, bwd2 = len(self.forward) > 1, len(self.backward) > 1
        f, b, ls = self.fwd_pkt_stats, self.bwd_pkt_stats, self.flow_length_stats
        out = {
            "Flow Duration": duration,
            # getFlowBytesPerSec / getFlowPacketsPerSec: divided unguarded by (double)duration / 1e6
            "Flow Bytes/s": java_divide(self.forward_bytes + self.backward_bytes, java_divide(duration, 1_000_000)),
            "Flow Packets/s": java_divide(self.packet_count(), java_divide(duration, 1_000_000)),
            "Flow IAT Mean": self.flow_iat.get_mean(),  # no guard: NaN without a gap
            "Flow IAT Std": self.flow_iat.get_standard_deviation(),
            "Flow IAT Max": self.flow_iat.max,
            "Flow IAT Min": self.flow_iat.min,
            "Min Packet Length": ls.min if any_pkt else 0,
            "Max Packet Length": ls.max if any_pkt else 0,
            "Packet Length Mean": ls.get_mean() if any_pkt else 0,
            "Packet Length Std": ls.get_standard_deviation() if any_pkt else 0,
            "Packet Length Variance": ls.get_variance() if any_pkt else 0,
            "FIN Flag Count": self.flag_counts["FIN"],
            "SYN Flag Count": self.flag_counts["SYN"],
            "RST Flag Count": self.flag_counts["RST"],
            "PSH Flag Count": self.flag_counts["PSH"],
            "ACK Flag Count": self.flag_counts["ACK"],
            "URG Flag Count": self.flag_counts["URG"],
            "CWE Flag Count": self.flag_counts["CWR"],  # the CICIDS2017 column name of CWR
            "ECE Flag Count": self.flag_counts["ECE"],
            # getDownUpRatio: (double)(backward.size() / forward.size()), integer division
            "Down/Up Ratio": float(len(self.backward) // len(self.forward)) if len(self.forward) > 0 else 0,
            # getAvgPacketSize: flowLengthStats' sum (first payload twice) over the packet count
            "Average Packet Size": ls.sum / self.packet_count() if self.packet_count() > 0 else 0,
            "Active Mean": self.flow_active.get_mean() if self.flow_active.n > 0 else 0,
            "Idle Mean": self.flow_idle.get_mean() if self.flow_idle.n > 0 else 0,
            "Idle Max": self.flow_idle.max if self.flow_idle.n > 0 else 0,
            "Total Fwd Packets": f.n,
            "Total Backward Packets": b.n,
            "Total Length of Fwd Packets": f.sum,
            "Total Length of Bwd Packets": b.sum,
            "Fwd Packet Length Max": f.max if f.n > 0 else 0,
            "Fwd Packet Length Min": f.min if f.n > 0 else 0,
            "Fwd Packet Length Mean": f.get_mean() if f.n > 0 else 0,
            "Fwd Packet Length Std": f.get_standard_deviation() if f.n > 0 else 0,
            "Bwd Packet Length Max": b.max if b.n > 0 else 0,
            "Bwd Packet Length Min": b.min if b.n > 0 else 0,
            "Bwd Packet Length Mean": b.get_mean() if b.n > 0 else 0,
            "Bwd Packet Length Std": b.get_standard_deviation() if b.n > 0 else 0,
            "Fwd IAT Total": self.forward_iat.sum if fwd2 else 0,
            "Fwd IAT Mean": self.forward_iat.get_mean() if fwd2 else 0,
            "Fwd IAT Std": self.forward_iat.get_standard_deviation() if fwd2 else 0,
            "Fwd IAT Max": self.forward_iat.max if fwd2 else 0,
            "Bwd IAT Total": self.backward_iat.sum if bwd2 else 0,
            "Bwd IAT Mean": self.backward_iat.get_mean() if bwd2 else 0,
            "Bwd IAT Std": self.backward_iat.get_standard_deviation() if bwd2 else 0,
            "Bwd IAT Max": self.backward_iat.max if bwd2 else 0,
            "Fwd Header Length": self.f_header_bytes,
            "Bwd Header Length": self.b_header_bytes,
        }
        return {k: float(v) for k, v in out.items()}


# --------------------------------------------------------------------------------------------
# FlowGenerator
# --------------------------------------------------------------------------------------------


class FlowGenerator:
    """FlowGenerator(bidirectional = true, flowTimeout, activityTimeout).addPacket."""

    def __init__(self, flow_timeout: int = FLOW_TIMEOUT_US, activity_timeout: int = ACTIVITY_TIMEOUT_US,
                 direction_by_port: bool = False) -> None:  # fmt: skip
        self.flow_timeout = flow_timeout
        self.activity_timeout = activity_timeout
        self.direction_by_port = direction_by_port
        self.current_flows: dict[tuple, BasicFlow] = {}
        self.finished_flows: list[BasicFlow] = []

    def _new_flow(self, packet: PacketInfo, flow_src: tuple | None = None) -> BasicFlow:
        return BasicFlow(packet, self.activity_timeout, self.direction_by_port, flow_src)

    def _finish(self, flow_id: tuple, flow: BasicFlow) -> None:
        # mListener.onFlowGenerated(flow) / finishedFlows.put(...); currentFlows.remove(id)
        self.finished_flows.append(flow)
        del self.current_flows[flow_id]

    def add_packet(self, packet: PacketInfo) -> None:
        current = packet.timestamp
        if packet.fwd_flow_id() in self.current_flows or packet.bwd_flow_id() in self.current_flows:
            flow_id = packet.fwd_flow_id() if packet.fwd_flow_id() in self.current_flows else packet.bwd_flow_id()
            flow = self.current_flows[flow_id]
            if current - flow.flow_start_time > self.flow_timeout:
                # flow timeout: the old flow is written if it has more than one packet, and a new
                # flow with the old one's orientation starts with this packet (under the same id)
                if flow.packet_count() > 1:
                    self.finished_flows.append(flow)
                del self.current_flows[flow_id]
                self.current_flows[flow_id] = self._new_flow(packet, (flow.src, flow.dst, flow.src_port, flow.dst_port))
            elif packet.has(FIN):
                if flow.is_forward(packet):
                    flow.f_fin_cnt += 1  # setFwdFINFlags()
                    if flow.f_fin_cnt == 1:
                        if flow.b_fin_cnt + flow.b_fin_cnt == 2:  # (sic: getBwdFINFlags() twice)
                            flow.add_packet(packet)
                            self._finish(flow_id, flow)
                        else:
                            flow.update_active_idle_time(current, self.activity_timeout)
                            flow.add_packet(packet)
                    # else: a second forward FIN is logged and dropped (joins no flow)
                else:
                    flow.b_fin_cnt += 1  # setBwdFINFlags()
                    if flow.b_fin_cnt == 1:
                        if flow.b_fin_cnt + flow.b_fin_cnt == 2:  # true at once: the first backward FIN closes
                            flow.add_packet(packet)
                            self._finish(flow_id, flow)
                        else:
                            flow.update_active_idle_time(current, self.activity_timeout)
                            flow.add_packet(packet)
                    # else: dropped
            elif packet.has(RST):
                flow.add_packet(packet)  # no updateActiveIdleTime here (only detectUpdateSubflows')
                self._finish(flow_id, flow)
            else:
                if flow.is_forward(packet) and flow.f_fin_cnt == 0:
                    flow.update_active_idle_time(current, self.activity_timeout)
                    flow.add_packet(packet)
                elif flow.b_fin_cnt == 0:
                    flow.update_active_idle_time(current, self.activity_timeout)
                    flow.add_packet(packet)
                # else: "FLOW already closed!": dropped
        else:
            self.current_flows[packet.fwd_flow_id()] = self._new_flow(packet)

    def written_flows(self) -> list[BasicFlow]:
        """What CICFlowMeter writes: finished flows, then the flows still current at the end of the
        capture (dumpLabeledCurrentFlow), each only with packetCount() > 1."""
        return [f for f in self.finished_flows + list(self.current_flows.values()) if f.packet_count() > 1]


# --------------------------------------------------------------------------------------------
# Entry point
# --------------------------------------------------------------------------------------------


@dataclass
class Flow:
    """One written flow: identity (the CSV's Source/Destination IP and port), and the 47 features."""

    src_ip: str
    src_port: int
    dst_ip: str
    dst_port: int
    protocol: int
    first_ts_us: int
    packets: int
    fragmented: bool
    features: dict[str, float]


def cicflowmeter_flows(path: Path, direction_by_port: bool = False, ipv6: bool = False) -> list[Flow]:
    """CICFlowMeter's flows of one pcap file (module docstring for the options)."""
    gen = FlowGenerator(direction_by_port=direction_by_port)
    for packet in read_packets(path, ipv6=ipv6):
        gen.add_packet(packet)
    out = []
    for fl in gen.written_flows():
        out.append(Flow(str(ipaddress.ip_address(fl.src)), fl.src_port, str(ipaddress.ip_address(fl.dst)), fl.dst_port,
                        fl.protocol, fl.flow_start_time, fl.packet_count(), fl.fragmented, fl.features()))  # fmt: skip
    return out
