"""flows: capture files -> packet table -> bidirectional flows -> per-flow sequences and 47 features.

`read_packets` (packets.py) decodes pcap/pcapng captures into numpy columns, `assemble`
(assemble.py) groups packets into flows, `flow_frame` (features.py) computes one row per flow.
`extract_flows` chains the three for the common case.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from .assemble import DEFAULT_MIN_PACKETS, MAX_PACKETS_PER_FLOW, VIEWS, FlowConfig, Flows, assemble
from .features import CSV_LEAD_COLUMNS, flow_frame
from .packets import PacketTable, read_packets
from .pcapio import CaptureError

__all__ = [
    "CSV_LEAD_COLUMNS", "DEFAULT_MIN_PACKETS", "MAX_PACKETS_PER_FLOW", "VIEWS", "CaptureError",
    "Extraction", "FlowConfig", "Flows", "PacketTable", "assemble", "extract_flows", "flow_frame",
    "read_packets",
]  # fmt: skip


@dataclass
class Extraction:
    packets: PacketTable
    flows: Flows
    frame: pd.DataFrame  # one row per flow (flows.features.flow_frame)


def extract_flows(
    paths: Sequence[str | Path],
    config: FlowConfig = FlowConfig(),
    points: Sequence[str] | None = None,
    allow_truncated: bool = False,
    sequences: bool = True,
) -> Extraction:
    packets = read_packets(paths, points=points, allow_truncated=allow_truncated)
    flows = assemble(packets, config)
    return Extraction(packets, flows, flow_frame(packets, flows, sequences=sequences))
