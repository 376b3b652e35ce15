"""`uavcas export --format csv`: one plain CSV row per flow, for CICIDS2017-style tooling.

Columns, in order (`csv_columns`):
- `Flow ID` (CICFlowMeter's key `<src>-<dst>-<src port>-<dst port>-<protocol>`), `Source IP`,
  `Source Port`, `Destination IP`, `Destination Port`, `Protocol`, `Timestamp` (the first
  packet's time, ISO 8601 UTC to the microsecond; CICFlowMeter writes local time to the second):
  CICIDS2017's names for our `src_ip` .. `protocol`, `first_ts_ns`;
- the dataset's 47 features under their own names: the `cic` standard's ARE CICIDS2017's column
  names and definitions (`uavcas.flows.standards.cic`); a `paper` dataset's are the authors' 47;
- every other column of the dataset under its uavcas name (run, scenario axes, counts, context
  columns, ground truth, per-family labels; `uavcas info DATASET --columns` explains each);
- `Label` last: the class (`label`; benign rows are `Benign`).
Left out: the per-packet sequences (`seq_*`: lists do not fit a CSV cell), and `first_ts` /
`last_ts` (rounded floats; `Timestamp`, `first_ts_ns` and `duration_s` say the same exactly).

NaN and infinity (`NONFINITE_TEXT`): written as CICFlowMeter's Java `Double.toString` writes
them, so as CICIDS2017's CSVs hold them: `NaN`, `Infinity`, `-Infinity` (a flow with a zero
duration has `Flow Bytes/s` and `Flow Packets/s` infinite, NaN when it carried no payload; a
one-packet flow's `Flow IAT *` are NaN). The store keeps a NaN as a Parquet null, so a null
float is `NaN` too. pandas reads them back as nan/inf. Any other null (an imported file's ports,
protocol) is an empty field. Strings are quoted only when
they hold a comma, a quote or a line break (RFC 4180).
"""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from uavcas.atomic import atomic_path
from uavcas.flows.standards import feature_columns
from uavcas.schema import SEQUENCE_COLUMNS
from uavcas.views import card_view

from .read import select_view
from .store import card_standard, read_card

ID_NAMES: dict[str, str] = {"src_ip": "Source IP", "src_port": "Source Port", "dst_ip": "Destination IP",
                            "dst_port": "Destination Port", "protocol": "Protocol"}
LEFT_OUT: tuple[str, ...] = SEQUENCE_COLUMNS + ("first_ts", "last_ts")
NONFINITE_TEXT: dict[str, str] = {"nan": "NaN", "inf": "Infinity", "-inf": "-Infinity"}
BATCH_ROWS = 65_536  # rows rendered at a time: bounded memory whatever the dataset's size


class CicCsvError(ValueError):
    """A dataset that cannot be written as a flow CSV; one line."""


def csv_columns(names: list[str], standard: str) -> list[str]:
    """The CSV header for a dataset whose columns are `names`."""
    feats = [f for f in feature_columns(standard) if f in names]
    used = set(ID_NAMES) | set(feats) | set(LEFT_OUT) | {"label"}
    rest = [c for c in names if c not in used]
    return ["Flow ID", *ID_NAMES.values(), "Timestamp", *feats, *rest, "Label"]


def _text(arr: pa.Array) -> pa.Array:
    """A column as its CSV fields (strings), nulls as empty fields."""
    t = arr.type
    if pa.types.is_floating(t):
        # the store writes pandas' NaN as a Parquet null (pyarrow from_pandas): a null float is NaN
        s = pc.fill_null(pc.cast(arr, pa.string()), "nan")
        for raw, text in NONFINITE_TEXT.items():
            s = pc.if_else(pc.equal(s, raw), pa.scalar(text), s)
    elif pa.types.is_string(t) or pa.types.is_large_string(t):
        needs = pc.match_substring_regex(arr, r'[,"\r\n]')
        quoted = pc.binary_join_element_wise('"', pc.replace_substring(arr, '"', '""'), '"', "")
        s = pc.if_else(needs, quoted, arr)
    else:
        s = pc.cast(arr, pa.string())
    return pc.fill_null(s, "")


def _flow_id(b: pa.RecordBatch) -> pa.Array:
    # CICFlowMeter's BasicFlow: src + "-" + dst + "-" + srcPort + "-" + dstPort + "-" + protocol
    parts = [pc.fill_null(pc.cast(b.column(c), pa.string()), "")
             for c in ("src_ip", "dst_ip", "src_port", "dst_port", "protocol")]
    return pc.binary_join_element_wise(*parts, "-")


def _timestamp(ns: pa.Array) -> pa.Array:
    us = pc.divide(ns, 1000).cast(pa.timestamp("us", tz="UTC"))  # int division: truncated, as CICFlowMeter's us
    return pc.replace_substring(pc.cast(us, pa.string()), " ", "T")


def _rows(b: pa.RecordBatch, header: list[str]) -> list[str]:
    """The CSV lines of a batch."""
    idx = {name: i for i, name in enumerate(b.schema.names)}
    cols = []
    for h in header:
        if h == "Flow ID":
            cols.append(_text(_flow_id(b)))
        elif h == "Timestamp":
            cols.append(_timestamp(b.column(idx["first_ts_ns"])))
        elif h == "Label":
            cols.append(_text(b.column(idx["label"])))
        else:
            src = next((k for k, v in ID_NAMES.items() if v == h), h)
            cols.append(_text(b.column(idx[src])))
    return pc.binary_join_element_wise(*cols, ",").to_pylist()


def write_flow_csv(dataset_dir: Path, out: Path, view: str | None = None) -> int:
    """Write DATASET_DIR's flows (of `view`, needed when it holds several) to the CSV file `out`;
    the number of rows written. Rows of a view that are no flows (window-host episodes) are refused."""
    card = read_card(dataset_dir)
    path = Path(dataset_dir) / "flows.parquet"
    spec = card_view(card)
    if not spec.is_flow:
        raise CicCsvError(f"{dataset_dir}: {spec.name} rows ({spec.row.plural}) are no flows and the csv format holds "
                          "one row per flow; extract the runs with `uavcas extract RUN --view 5tuple` (or hostpair) "
                          "into another dataset and export that")
    standard = card_standard(card)
    names = [n for n in pq.read_schema(path).names if n not in LEFT_OUT]
    if "view" in names:  # one view only: a dataset extracted with several holds the same traffic twice
        views = pq.read_table(path, columns=["view"]).to_pandas()
        select_view(views, view)
    elif view is not None:
        raise CicCsvError(f"--view {view}: this dataset has no 'view' column")
    missing = [c for c in ("first_ts_ns", "label", *ID_NAMES) if c not in names]
    if missing:
        raise CicCsvError(f"{path}: lacks the columns {missing}")
    header = csv_columns(names, standard)
    n = 0
    pf = pq.ParquetFile(path)
    with atomic_path(out) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(header) + "\n")  # the names hold no comma or quote
        for b in pf.iter_batches(batch_size=BATCH_ROWS, columns=names):
            if view is not None:
                b = b.filter(pc.equal(b.column(b.schema.names.index("view")), view))
            lines = _rows(b, header)
            fh.write("".join(line + "\n" for line in lines))
            n += len(lines)
    return n
