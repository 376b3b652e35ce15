"""The UAV's telemetry radio on the air: sends its precomputed RADIO_STATUS after each heartbeat.

What it reports and why from there: `radio` (the pure model). Here only the sending: its own
pymavlink MAVLink object with the radio's ids (SiK's '3'/'D') and its own sequence numbers (a
SiK radio counts its own `seqnum`, mavlink.c), unsigned (SiK never signs), on the autopilot's UDP
socket to the GCS's address: the one flow a WiFi bridge's report shares with the vehicle's.
"""

from __future__ import annotations

import socket
from collections import Counter

from . import radio
from .link import Peer
from .specs import UavSpec


class RadioBridge:
    """Sends `spec.radio`'s report of the current second; nothing when the spec has no radio."""

    def __init__(self, sock: socket.socket, spec: UavSpec) -> None:
        self.radio, self.sent = spec.radio, Counter()
        self.peer = (None if spec.radio is None else
                     Peer(sock, (spec.gcs_ip, spec.gcs_port), spec.radio.sysid, spec.radio.compid, self.sent))

    def after_heartbeat(self, t_s: float) -> None:
        """SiK injects one report per heartbeat it passes on (radio.py): call right after one."""
        if self.peer is None:
            return
        report = self.radio.report_at(t_s)
        if report is not None:
            self.peer.send(radio.message(report))
