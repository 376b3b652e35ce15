"""MAVLink in a run's captures: every message of every capture point, decoded, with its packet's truth.

`mavlink_table(run_dir)` reads the run's captures (RUN_DIR/pcap, one per switch) with the project's
reader (`uavcas.flows.read_packets`, so its rows are the rows the extraction labels), keeps the
UDP datagrams to or from the MAVLink port (14550 unless told), takes each one's payload from the
raw capture records (`uavcas.flows.pcapio`, the same records the packet table was decoded from:
joined on (capture point, frame_index)) and decodes it with pymavlink's parser. One row per
message: a datagram holding several messages gives several rows, in the order they came
(`msg_index`); a datagram from which nothing parses gives one row with `msg_name` missing and
`crc_ok` False. Each row carries the effect and family of its packet from the run's ground truth
(`uavcas.labels.packet_truth`, as `uavcas.extract` computes it).

Why a module of its own, above `uavcas.flows` and `uavcas.labels`: it needs both (the capture
reader and the truth), and neither may depend on the other's consumers; like `uavcas.extract`, it
is a stage that joins them, for users reading a run (`uavcas mavlink RUN_DIR`).

A packet seen at k switches is k observations, and each gives its messages a row with its
capture point (`point`): counting messages means choosing one point (`point=` / `--point`),
e.g. the sender's switch, or de-duplicating on (sysid, compid, seq, msg_id, ts).

Columns (`COLUMNS`, then `POSITION_COLUMNS`, then effect and family):
  ts_s float64 (Unix seconds), ts_ns int64 (Unix ns, exact), point (capture point), src_ip,
  src_port, dst_ip, dst_port, packet_row (row of the run's packet table: the join key),
  frame_index (record number in its capture file), msg_index (position in the datagram),
  mavlink_version (1 or 2), sysid, compid, seq, msg_id, msg_name, crc_ok (True: the CRC,
  including the message's CRC extra, matched; False: it did not, or nothing parsed; missing: a
  message id the dialect does not know, whose CRC cannot be checked), error (why a row is not a
  good message, else missing), fields_json (the decoded fields as a JSON object; missing unless
  crc_ok), the position fields the message has in its own units (`POSITION_COLUMNS`,
  `<field>_<unit>`, e.g. lat_degE7, alt_mm, vx_cm_s, hdg_cdeg; missing where it has none),
  offset_east_m, offset_north_m, offset_up_m float64 (`OFFSET_COLUMNS`: a UAV's position report,
  GLOBAL_POSITION_INT or GPS_RAW_INT with a good CRC, minus the plan's track of the UAV with that
  sysid at the message's own time, time_boot_ms (ms since the run's t0), both in the plan's
  tangent plane at `Plan.site`; ~0 for a true report (lat/lon in 1e-7 degrees: ~1 cm), the
  spoofer's drift for a `gps_spoof` victim's; missing for other messages),
  effect (`vocabulary.EFFECTS`) and family (`vocabulary.FAMILIES`; missing for benign and
  channel_loss).
For a row whose CRC failed, sysid/compid/seq/msg_id/msg_name are what its header claims.
A UAV radio's RADIO_STATUS (`traffic.mavlink.radio`) carries SiK's ids, sysid 51 / compid 68,
for every UAV, as real SiK radios do: its UAV is its src_ip, not its sysid.
"""

from __future__ import annotations

import importlib
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from uavcas.atomic import atomic_path
from uavcas.extract import run_inputs, run_truth
from uavcas.flows import read_packets
from uavcas.flows.decode import link_layer
from uavcas.flows.packets import addresses_to_str, ns_to_s
from uavcas.flows.pcapio import iter_capture
from uavcas.rundir import RunDir
from uavcas.twin.track import Track, geodetic_to_local
from uavcas.vocabulary import EFFECTS, FAMILIES

MAVLINK_PORT = 14550
TABLE_SUFFIXES = (".parquet", ".csv")  # what `write_table` writes, by the file's suffix
DEFAULT_DIALECT = "ardupilotmega"  # pymavlink's own default; a superset of common
POSITION_FIELDS: tuple[str, ...] = ("lat", "lon", "alt", "relative_alt", "vx", "vy", "vz", "hdg")
# Every unit these fields carry in pymavlink's dialects, and the column's dtype: integer units
# stay exact (nullable Int64), float ones float64. A field whose unit is not here stays in fields_json.
POSITION_UNITS: dict[str, dict[str, str]] = {
    "lat": {"degE7": "Int64", "deg": "float64"},
    "lon": {"degE7": "Int64", "deg": "float64"},
    "alt": {"mm": "Int64", "m": "float64"},
    "relative_alt": {"mm": "Int64"},
    "vx": {"cm/s": "Int64", "m/s": "float64"},
    "vy": {"cm/s": "Int64", "m/s": "float64"},
    "vz": {"cm/s": "Int64", "m/s": "float64"},
    "hdg": {"cdeg": "Int64", "rad": "float64"},
}


def position_column(field: str, unit: str) -> str:
    """'vx', 'cm/s' -> 'vx_cm_s': the unit in the name, spelled for a column."""
    return f"{field}_{unit.replace('/', '_')}"


POSITION_COLUMNS: dict[str, str] = {position_column(f, u): dt for f, units in POSITION_UNITS.items()
                                    for u, dt in units.items()}  # fmt: skip
COLUMNS: dict[str, str] = {
    "ts_s": "float64", "ts_ns": "int64", "point": "object", "src_ip": "object", "src_port": "uint16",
    "dst_ip": "object", "dst_port": "uint16", "packet_row": "int64", "frame_index": "int64", "msg_index": "int16",
    "mavlink_version": "UInt8", "sysid": "UInt8", "compid": "UInt8", "seq": "UInt8", "msg_id": "UInt32",
    "msg_name": "object", "crc_ok": "boolean", "error": "object", "fields_json": "object",
}  # fmt: skip
# what one datagram's decoding gives (the rest of COLUMNS comes from the packet table)
DECODED_COLUMNS: tuple[str, ...] = ("msg_index", *list(COLUMNS)[list(COLUMNS).index("mavlink_version"):])
OFFSET_COLUMNS: dict[str, str] = {"offset_east_m": "float64", "offset_north_m": "float64", "offset_up_m": "float64"}
# the reports a GPS fix feeds, and the field holding each one's time since boot, in ms per unit
REPORT_TIME_FIELDS: dict[str, tuple[str, float]] = {"GLOBAL_POSITION_INT": ("time_boot_ms", 1.0),
                                                    "GPS_RAW_INT": ("time_usec", 1e-3)}
TRUTH_COLUMNS: dict[str, str] = {"effect": "object", "family": "object"}
ALL_COLUMNS: dict[str, str] = {**COLUMNS, **POSITION_COLUMNS, **OFFSET_COLUMNS, **TRUTH_COLUMNS}
UDP = 17
UDP_HEADER = 8
V1_MAGIC, V2_MAGIC = 0xFE, 0xFD


class MavlinkError(ValueError):
    """A run directory whose MAVLink cannot be read; one-line message."""


def load_dialect(name: str = DEFAULT_DIALECT) -> ModuleType:
    """pymavlink's generated MAVLink 2 module of a dialect (it parses MAVLink 1 frames too)."""
    try:
        return importlib.import_module(f"pymavlink.dialects.v20.{name}")
    except ModuleNotFoundError:
        raise MavlinkError(f"unknown MAVLink dialect {name!r} (pymavlink.dialects.v20 has no such module)") from None


# --- one datagram -> message rows ------------------------------------------------------------------


def _header(frame: bytes | bytearray) -> dict[str, int] | None:
    """The header fields of a MAVLink 1 or 2 frame, or None when `frame` does not start with one."""
    if len(frame) >= 10 and frame[0] == V2_MAGIC:
        return {"mavlink_version": 2, "seq": frame[4], "sysid": frame[5], "compid": frame[6],
                "msg_id": frame[7] | (frame[8] << 8) | (frame[9] << 16)}
    if len(frame) >= 6 and frame[0] == V1_MAGIC:
        return {"mavlink_version": 1, "seq": frame[2], "sysid": frame[3], "compid": frame[4], "msg_id": frame[5]}
    return None


def _json_value(v: Any) -> Any:
    # JSON has no NaN/inf and no bytes: spell them so the column stays valid JSON
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    if isinstance(v, (bytes, bytearray)):
        return v.hex()
    if isinstance(v, (list, tuple)):
        return [_json_value(x) for x in v]
    return v


def decode_datagram(payload: bytes, dialect: ModuleType) -> list[dict[str, Any]]:
    """The message rows of one UDP payload (columns mavlink_version .. fields_json and the position
    columns; missing ones absent). A fresh parser per datagram: a UDP datagram is whole, so a
    frame cut at its end must not swallow the next datagram's bytes."""
    mav = dialect.MAVLink(None)
    mav.robust_parsing = True  # bad bytes and CRC failures come back as BAD_DATA, not exceptions
    try:
        msgs = mav.parse_buffer(payload) or []
    except dialect.MAVError as exc:  # robust parsing should not raise; a row says it if it does
        return [{"crc_ok": False, "error": f"parser: {exc.message}"}]
    rows: list[dict[str, Any]] = []
    for m in msgs:
        if isinstance(m, dialect.MAVLink_bad_data):
            hdr = _header(m.data) or {}
            row: dict[str, Any] = {**hdr, "crc_ok": False, "error": str(m.reason)}
            if "msg_id" in hdr:
                cls = dialect.mavlink_map.get(hdr["msg_id"])
                row["msg_name"] = cls.msgname if cls is not None else None
        elif isinstance(m, dialect.MAVLink_unknown):
            row = {**(_header(m.get_msgbuf()) or {}), "crc_ok": pd.NA,
                   "error": "message id not in the dialect: CRC not checkable"}
        else:
            row = {"mavlink_version": 2 if m.get_msgbuf()[0] == V2_MAGIC else 1, "seq": m.get_seq(),
                   "sysid": m.get_srcSystem(), "compid": m.get_srcComponent(), "msg_id": m.get_msgId(),
                   "msg_name": m.get_type(), "crc_ok": True}
            fields = {k: getattr(m, k) for k in m.get_fieldnames()}
            row["fields_json"] = json.dumps({k: _json_value(v) for k, v in fields.items()}, allow_nan=False)
            units = type(m).fieldunits_by_name
            for f in POSITION_FIELDS:
                unit = units.get(f)
                if f in fields and unit in POSITION_UNITS[f]:
                    row[position_column(f, unit)] = fields[f]
        rows.append(row)
    left = mav.buf_len()
    if left:  # an incomplete frame at the end of the datagram
        tail = bytes(mav.buf[mav.buf_index:])
        rows.append({**(_header(tail) or {}), "crc_ok": False,
                     "error": f"frame cut at the end of the datagram ({left} bytes left)"})
        hdr_id = rows[-1].get("msg_id")
        if hdr_id is not None and hdr_id in dialect.mavlink_map:
            rows[-1]["msg_name"] = dialect.mavlink_map[hdr_id].msgname
    if not rows:
        rows.append({"crc_ok": False, "error": "empty datagram"})
    return rows


def decode_datagrams(payloads: Sequence[bytes], dialect: ModuleType | str = DEFAULT_DIALECT) -> pd.DataFrame:
    """Message rows of many datagrams: `datagram` (index into `payloads`), `msg_index` and the
    decoded columns of `COLUMNS` from mavlink_version on, plus `POSITION_COLUMNS`, typed."""
    mod = load_dialect(dialect) if isinstance(dialect, str) else dialect
    rows: list[dict[str, Any]] = []
    for k, data in enumerate(payloads):
        for i, r in enumerate(decode_datagram(data, mod)):
            r["datagram"], r["msg_index"] = k, i
            rows.append(r)
    cols = ["datagram", *DECODED_COLUMNS, *POSITION_COLUMNS]
    df = pd.DataFrame.from_records(rows, columns=cols)
    return df.astype({"datagram": "int64", **{c: ALL_COLUMNS[c] for c in cols[1:]}})


# --- captures -> payloads ---------------------------------------------------------------------------


def udp_payloads(path: str | Path, frame_index: np.ndarray, ip_hdr_len: np.ndarray, ip_len: np.ndarray,
                 allow_truncated: bool = False) -> list[bytes]:
    """The UDP payloads of records `frame_index` (sorted ascending) of one capture file, from the
    packet table's own header lengths: the payload starts after the link layer, the IP header
    (options / extension headers included) and the 8-byte UDP header, and ends where the IP
    length says (Ethernet padding of a short frame is not payload) or the snap length cut it."""
    out: list[bytes] = [b""] * int(frame_index.shape[0])
    if not frame_index.shape[0]:
        return out
    for raw in iter_capture(path, allow_truncated=allow_truncated):
        lo, hi = raw.first_record, raw.first_record + raw.n
        a, b = np.searchsorted(frame_index, [lo, hi])
        if a == b:
            continue
        rec = frame_index[a:b] - lo
        _, l3, _ = link_layer(raw)
        start = l3[rec] + ip_hdr_len[a:b].astype(np.int64) + UDP_HEADER
        stop = np.minimum(l3[rec] + ip_len[a:b].astype(np.int64),
                          raw.data_off[rec] + raw.cap_len[rec].astype(np.int64))
        buf = raw.buf
        for j, (s, e) in enumerate(zip(start.tolist(), stop.tolist())):
            out[a + j] = buf[s:e].tobytes() if e > s else b""
    return out


@dataclass(frozen=True)
class RunPackets:
    """A run's packet table, its capture files (one per point) and every row's truth."""

    packets: Any  # uavcas.flows.PacketTable
    plan: Any  # uavcas.twin.model.Plan
    pcaps: list[Path]
    effect: np.ndarray  # int8 per row, index into EFFECTS
    family: np.ndarray  # int8 per row, index into FAMILIES, -1: none


def run_packets(run_dir: str | Path, allow_truncated: bool = False) -> RunPackets:
    """Read a run's captures and compute each packet's truth the way `uavcas.extract` does (same
    reader, same capture-point names, same follower and rules), so rows and truths line up."""
    rd = RunDir(Path(run_dir))
    plan, pcaps, t0 = run_inputs(rd)
    packets = read_packets(pcaps, points=[p.stem for p in pcaps], allow_truncated=allow_truncated)
    _, _, truth = run_truth(rd, packets, plan, t0)
    return RunPackets(packets, plan, pcaps, truth.effect, truth.family)


def mavlink_rows(packets, port: int = MAVLINK_PORT) -> np.ndarray:
    """Packet-table rows of UDP datagrams to or from `port` that carry their UDP header (a later IP
    fragment carries its datagram's ports but no header: its bytes are not a MAVLink frame start)."""
    sel = ((packets["proto"] == UDP) & ((packets["sport"] == port) | (packets["dport"] == port))
           & (packets["l4_hdr_len"] > 0))
    return np.flatnonzero(sel)


def mavlink_table(run_dir: str | Path, port: int = MAVLINK_PORT, point: str | None = None,
                  dialect: str = DEFAULT_DIALECT, allow_truncated: bool = False) -> pd.DataFrame:
    """Every MAVLink message in a run's captures, one row per message and capture point (module
    docstring). `point`: keep one capture point's observations (e.g. "s-uav0")."""
    if not 0 < port < 65536:
        raise MavlinkError(f"port {port} is not a UDP port (1..65535)")
    mod = load_dialect(dialect)
    rp = run_packets(run_dir, allow_truncated=allow_truncated)
    p = rp.packets
    if point is not None and point not in p.points:
        raise MavlinkError(f"{run_dir}: no capture point {point!r} (points: {', '.join(p.points)})")
    rows = mavlink_rows(p, port)
    if point is not None:
        rows = rows[p["point"][rows] == p.points.index(point)]
    # payloads per capture file, in record order (one pass over each file)
    payloads: list[bytes] = [b""] * rows.shape[0]
    pts = p["point"][rows]
    for k, path in enumerate(rp.pcaps):
        mine = np.flatnonzero(pts == k)
        if not mine.shape[0]:
            continue
        r = rows[mine]
        order = np.argsort(p["frame_index"][r], kind="stable")
        r, mine = r[order], mine[order]
        got = udp_payloads(path, p["frame_index"][r], p["ip_hdr_len"][r], p["ip_len"][r], allow_truncated)
        for j, data in zip(mine.tolist(), got):
            payloads[j] = data
    msgs = decode_datagrams(payloads, mod)
    r = rows[msgs.pop("datagram").to_numpy()]
    ts = p["ts_ns"][r]
    fam = rp.family[r].astype(np.int64)
    out = pd.DataFrame({
        "ts_s": ns_to_s(ts), "ts_ns": ts, "point": np.asarray(p.points, dtype=object)[p["point"][r]],
        "src_ip": addresses_to_str(p["src_hi"][r], p["src_lo"][r]), "src_port": p["sport"][r],
        "dst_ip": addresses_to_str(p["dst_hi"][r], p["dst_lo"][r]), "dst_port": p["dport"][r],
        "packet_row": r.astype(np.int64), "frame_index": p["frame_index"][r],
    })  # fmt: skip
    out = pd.concat([out, msgs], axis=1)
    out = pd.concat([out, report_offsets(out, rp.plan)], axis=1)
    out["effect"] = np.asarray(EFFECTS, dtype=object)[rp.effect[r].astype(np.int64)]
    out["family"] = np.where(fam >= 0, np.asarray(FAMILIES, dtype=object)[np.maximum(fam, 0)], None)
    out = out[list(ALL_COLUMNS)].astype(ALL_COLUMNS)
    return out.sort_values(["ts_ns", "point", "packet_row", "msg_index"], kind="stable").reset_index(drop=True)


def report_offsets(table: pd.DataFrame, plan) -> pd.DataFrame:
    """`OFFSET_COLUMNS` of each row of `table` (module docstring): claimed minus true position of a
    UAV's good GLOBAL_POSITION_INT / GPS_RAW_INT, in metres east, north, up; NaN elsewhere."""
    out = pd.DataFrame(np.nan, index=table.index, columns=list(OFFSET_COLUMNS))
    uav_of = {n.sysid: n.name for n in plan.nodes if n.kind == "uav" and n.sysid is not None}
    tracks: dict[str, Track] = {}
    good = table["crc_ok"].fillna(False).astype(bool) & table["msg_name"].isin(list(REPORT_TIME_FIELDS))
    for i, row in table[good].iterrows():
        uav = uav_of.get(int(row["sysid"]))
        if uav is None:
            continue
        fields = json.loads(row["fields_json"])
        name, per_ms = REPORT_TIME_FIELDS[row["msg_name"]]
        true = (tracks.get(uav) or tracks.setdefault(uav, Track.of(plan, uav))).at(fields[name] * per_ms / 1000.0)
        x, y, z = geodetic_to_local(plan.site, fields["lat"] / 1e7, fields["lon"] / 1e7, fields["alt"] / 1000.0)
        out.loc[i] = (x - true.x_m, y - true.y_m, z - true.z_m)
    return out


def problems(table: pd.DataFrame) -> list[str]:
    """One line per kind of row that is not a good message (for a warning on stderr)."""
    out = []
    unparsed = table["msg_name"].isna() & table["msg_id"].isna()
    if unparsed.any():
        n = int(table.loc[unparsed, ["point", "packet_row"]].drop_duplicates().shape[0])
        out.append(f"{int(unparsed.sum())} row(s) from {n} datagram observation(s) hold no MAVLink frame "
                   "(msg_name missing, crc_ok False)")
    bad_crc = (table["crc_ok"] == False) & ~unparsed  # noqa: E712  (nullable boolean: NA stays out)
    if bad_crc.any():
        out.append(f"{int(bad_crc.sum())} message(s) failed their CRC (or were cut); their header fields are "
                   "what the header claims")
    unknown = table["crc_ok"].isna()
    if unknown.any():
        out.append(f"{int(unknown.sum())} message(s) have an id the dialect does not know (CRC not checked)")
    return out


def message_counts(table: pd.DataFrame, point: str | None = None) -> pd.DataFrame:
    """Good messages (crc_ok) per sysid, msg_name and whole Unix second (`second`), at one capture
    point (`point`, else every observation counts): columns sysid, msg_name, second, messages.
    For checking a stream against its configured rates."""
    t = table[table["crc_ok"].fillna(False).astype(bool)]
    if point is not None:
        t = t[t["point"] == point]
    sec = (t["ts_ns"] // 1_000_000_000).rename("second")
    return (t.groupby([t["sysid"], t["msg_name"], sec]).size().rename("messages").reset_index()
            .astype({"sysid": "UInt8", "second": "int64", "messages": "int64"}))


def write_table(table: pd.DataFrame, path: str | Path) -> Path:
    """The table as Parquet (zstd) or CSV, by the suffix of `path` (`TABLE_SUFFIXES`), atomically."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in TABLE_SUFFIXES:
        raise MavlinkError(f"{path} must end in {' or '.join(TABLE_SUFFIXES)}")
    with atomic_path(path) as tmp:
        if suffix == ".parquet":
            pq.write_table(pa.Table.from_pandas(table, preserve_index=False), tmp, compression="zstd")
        else:
            table.to_csv(tmp, index=False)
    return path
