"""flows: capture files -> packet table -> bidirectional flows -> per-flow sequences and 47 features.

`read_packets` (packets.py) decodes pcap/pcapng captures block by block into numpy columns
(pcapio.py framing, decode.py protocols, fragments.py IP fragments), `assemble` (assemble.py)
groups packets into flows (termination.py: the `connection`, `cic` and `timeout` policies),
`flow_frame` (features.py) computes one row per flow with the features of a standard
(`standards`: one module per standard; cic: CICFlowMeter's, paper: the authors'). `extract_flows`
(`flows_of` for a table already read) chains the three in memory (the extraction stage needs the packets for its
labels); `iter_flow_frames` (stream.py) streams one capture with bounded memory; `uavcas.dataset.flow_files`
writes such a stream to Parquet or CSV.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from .assemble import MAX_PACKETS_PER_FLOW, VIEWS, FlowConfig, Flows, assemble
from .features import CSV_LEAD_COLUMNS, flow_frame
from .packets import CaptureStats, PacketTable, read_packets
from .pcapio import CaptureError
from .standards import DEFAULT_STANDARD
from .stream import StreamReport, empty_flow_frame, iter_flow_frames
from .termination import TERMINATIONS

__all__ = [
    "CSV_LEAD_COLUMNS", "MAX_PACKETS_PER_FLOW", "TERMINATIONS", "VIEWS", "CaptureError",
    "CaptureStats", "Extraction", "FlowConfig", "Flows", "PacketTable", "StreamReport", "assemble",
    "empty_flow_frame", "extract_flows", "flow_frame", "flows_of", "iter_flow_frames", "read_packets",
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
    standard: str = DEFAULT_STANDARD,
) -> Extraction:
    packets = read_packets(paths, points=points, allow_truncated=allow_truncated)
    return flows_of(packets, config, sequences=sequences, standard=standard)


def flows_of(
    packets: PacketTable,
    config: FlowConfig = FlowConfig(),
    transmissions=None,
    sequences: bool = True,
    standard: str = DEFAULT_STANDARD,
) -> Extraction:
    """Flows and their rows from a packet table already read (`transmissions`: `assemble`'s)."""
    flows = assemble(packets, config, transmissions=transmissions)
    return Extraction(packets, flows, flow_frame(packets, flows, sequences=sequences, standard=standard))
