"""`uavcas flows | extract | export | import | info`: captures -> flows -> labeled dataset -> files."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import typer
from rich.table import Table

from uavcas.dataset.read import EXPORT_FORMATS, IMPORT_FORMATS
from uavcas.flows.assemble import VIEWS
from uavcas.flows.standards import DEFAULT_STANDARD, names, standards
from uavcas.flows.termination import TERMINATIONS
from uavcas.schema import EPISODE_VIEW
from uavcas.vocabulary import LABEL_MODES

from .common import (TERMINATION_HELP, atomic_path, check_output, console, dataset_argument, err_console, fail, one_of,
                     run_dir_argument)

View = one_of(VIEWS)
ExtractView = one_of((*VIEWS, EPISODE_VIEW))
Standard = one_of(names())
Termination = one_of(TERMINATIONS)
FlowsFormat = one_of(("table", "csv", "parquet"))

TABLE_ROWS = 50  # the human-readable table shows this many flows; csv/parquet have them all
FEATURES_HELP = "Feature standard: " + "; ".join(f"{s.name} ({s.summary})" for s in standards()) + "."


def _errors():
    from uavcas.dataset.external import ExternalFormatError
    from uavcas.dataset.store import DatasetError
    from uavcas.dataset.uavcas_csv import CsvFormatError
    from uavcas.flows import CaptureError
    from uavcas.labels import LabelError

    return (CaptureError, DatasetError, LabelError, CsvFormatError, ExternalFormatError, ValueError, OSError)


def _warn(lines) -> None:
    for line in lines:
        err_console.print(f"[yellow]warning:[/] {line}", highlight=False, soft_wrap=True)


def _report_warnings(report) -> None:
    _warn(f"{t.path} is truncated at byte offset {t.offset}; kept the packets before it" for t in report.truncations)
    for st in report.stats:
        _warn(st.warnings())


def _ns_decimal(ns):
    """int64 Unix ns -> Arrow decimal128(28, 9) seconds: exact, written with all 9 digits."""
    import numpy as np
    import pyarrow as pa

    ns = np.asarray(ns, dtype=np.int64)
    words = np.zeros((ns.shape[0], 2), dtype=np.int64)
    words[:, 0], words[:, 1] = ns, np.where(ns < 0, -1, 0)  # the unscaled 128-bit integer
    return pa.Array.from_buffers(pa.decimal128(28, 9), ns.shape[0], [None, pa.py_buffer(words.tobytes())])


def _csv_table(df, features):
    """The CSV columns of a flow frame as an Arrow table (Arrow's writer is what keeps CSV fast)."""
    import pyarrow as pa

    from uavcas.dataset.parquet import frame_to_arrow
    from uavcas.flows import CSV_LEAD_COLUMNS

    t = frame_to_arrow(df[list(CSV_LEAD_COLUMNS) + list(features)])
    first = df["first_ts_ns"].to_numpy()
    last = first + (df["duration_s"].to_numpy() * 1e9).round().astype("int64")
    t = t.append_column("first_ts", _ns_decimal(first)).append_column("last_ts", _ns_decimal(last))
    return t.append_column("capture_point", pa.array(df["capture_point"].astype(str).tolist(), pa.string()))


def _empty_frame(features: str):
    """The columns of a flow frame with no rows (a capture without a single flow)."""
    from uavcas.flows import PacketTable, assemble, flow_frame
    from uavcas.flows.packets import empty_columns

    empty = PacketTable(empty_columns(), ("none",))
    return flow_frame(empty, assemble(empty), standard=features)


def flows_cmd(
    pcaps: list[Path] = typer.Argument(..., help="Capture file(s), pcap or pcapng; several = capture points."),
    view: View = typer.Option("5tuple", "--view", help="Flow key: 5tuple or hostpair (the authors')."),
    features: Standard = typer.Option(DEFAULT_STANDARD, "--features", help=FEATURES_HELP),
    min_packets: int = typer.Option(None, "--min-packets", help="Drop smaller flows (default 1 for 5tuple, 2 under --termination cic, 10 for hostpair)."),
    fmt: FlowsFormat = typer.Option("table", "--format", help="table, csv or parquet."),
    out: Path = typer.Option(None, "--out", help="Output file (default: standard output; required for parquet)."),
    allow_truncated: bool = typer.Option(False, "--allow-truncated", help="Keep the packets before a truncation."),
    termination: Termination | None = typer.Option(None, "--termination", help=TERMINATION_HELP),
    idle_timeout: float = typer.Option(None, "--idle-timeout", help="Idle timeout in s; 0 = none (default: connection 15, cic none, timeout 120)."),
    active_timeout: float = typer.Option(None, "--active-timeout", help="Active timeout in s; 0 = none (default: connection and cic 120, timeout 1800)."),
    close_grace: float = typer.Option(None, "--close-grace", help="connection: s after a close during which the connection's packets join it (default 60)."),
) -> None:
    """Flows of one capture (streamed, bounded memory) or of several capture points (de-duplicated)."""
    from uavcas.atomic import check_target
    from uavcas.dataset.parquet import frame_to_arrow
    from uavcas.flows import FlowConfig, StreamReport, iter_flow_frames
    from uavcas.flows.standards import feature_columns

    if fmt == "parquet" and out is None:
        raise fail("--format parquet needs --out FILE")
    if out is not None:
        check_output(out, "file")
    report = StreamReport()
    try:
        if out is not None:
            check_target(out)
        cfg = FlowConfig(view=view, termination=termination, min_packets=min_packets, idle_timeout_s=idle_timeout,  # type: ignore[arg-type]
                         active_timeout_s=active_timeout, grace_s=close_grace)  # fmt: skip
        frames = iter_flow_frames(pcaps, cfg, standard=features, sequences=fmt == "parquet",
                                  allow_truncated=allow_truncated, report=report)  # fmt: skip
        if fmt == "parquet":
            import pyarrow.parquet as pq

            with atomic_path(out) as tmp:
                writer = None
                for df in frames:
                    t = frame_to_arrow(df)
                    writer = writer or pq.ParquetWriter(tmp, t.schema, compression="zstd")
                    writer.write_table(t.cast(writer.schema))
                if writer is None:  # no flow at all: still a valid (empty) file
                    writer = pq.ParquetWriter(tmp, frame_to_arrow(_empty_frame(features)).schema)
                writer.close()
            _report_warnings(report)
            err_console.print(f"wrote {report.flows} flows to {out}", highlight=False)
            return
        if fmt == "csv":
            import pyarrow.csv as pacsv

            cols = feature_columns(features)

            def write_csv(fh) -> None:
                # the header plain (fixed names, no commas), the rows by Arrow (strings quoted)
                opts = pacsv.WriteOptions(include_header=False, quoting_style="needed")
                writer = None
                for df in frames:
                    t = _csv_table(df, cols)
                    if writer is None:
                        fh.write((",".join(t.schema.names) + "\n").encode())
                        writer = pacsv.CSVWriter(fh, t.schema, write_options=opts)
                    writer.write_table(t)
                if writer is None:  # no flow: the header alone
                    fh.write((",".join(_csv_table(_empty_frame(features), cols).schema.names) + "\n").encode())
                else:
                    writer.close()

            if out is None:
                sys.stdout.flush()
                write_csv(sys.stdout.buffer)
                sys.stdout.buffer.flush()
            else:
                with atomic_path(out) as tmp, open(tmp, "wb") as fh:
                    write_csv(fh)
            _report_warnings(report)
            return
        shown = []
        for df in frames:
            if sum(len(d) for d in shown) < TABLE_ROWS:
                shown.append(df.head(TABLE_ROWS))
    except _errors() as exc:
        raise fail(str(exc)) from None
    _report_warnings(report)
    import pandas as pd

    head = pd.concat(shown, ignore_index=True).head(TABLE_ROWS) if shown else None
    table = Table(title=f"{report.flows} flows ({view}) from {report.packets} packets")
    for c in ("src", "dst", "proto", "packets", "bytes", "duration_s", "point"):
        table.add_column(c, justify="right" if c in ("packets", "bytes", "duration_s") else "left")
    for r in head.itertuples(index=False) if head is not None else []:
        table.add_row(
            f"{r.src_ip}:{r.src_port}", f"{r.dst_ip}:{r.dst_port}", str(r.protocol),
            str(r.packets), str(r.bytes), f"{r.duration_s:.6f}", str(r.capture_point),
        )  # fmt: skip
    if report.flows > TABLE_ROWS:
        table.caption = f"first {TABLE_ROWS} of {report.flows} flows; use --format csv for all"
    from rich.console import Console

    if out is None:  # addresses must not be cut: print wide even when stdout is not a terminal
        Console(width=max(console.width, 140)).print(table)
    else:
        buf = io.StringIO()
        Console(file=buf, width=160).print(table)
        try:
            with atomic_path(out) as tmp:
                tmp.write_text(buf.getvalue())
        except _errors() as exc:
            raise fail(str(exc)) from None


def extract_cmd(
    run_dir: Path = run_dir_argument(),
    out: Path = typer.Option(..., "--out", help="Dataset directory to add the run's shard to."),
    view: ExtractView = typer.Option("5tuple", "--view", help="Flow key: 5tuple, hostpair or window-hostpair (one flow per host pair per plan window); "
                                                   "or window-host: episodes, one row per node per plan window (collaborative classes)."),
    features: Standard = typer.Option(DEFAULT_STANDARD, "--features", help=FEATURES_HELP),
    labels: one_of(LABEL_MODES) = typer.Option("ours", "--labels", help="ours (from each packet's effect) or paper (IP membership)."),
    min_packets: int = typer.Option(None, "--min-packets", help="Drop smaller flows (default by view)."),
    termination: Termination | None = typer.Option(None, "--termination", help=TERMINATION_HELP),
    allow_truncated: bool = typer.Option(False, "--allow-truncated", help="Keep the packets before a truncation."),
    min_attack_fraction: float = typer.Option(
        0.0, "--min-attack-fraction", min=0.0, max=1.0,
        help="Leave out flows whose share of attack packets is above 0 but below this (default 0: keep all)."),
    allow_incomplete: bool = typer.Option(False, "--allow-incomplete",
                                          help="Also extract a run that was killed or failed (marked incomplete)."),
) -> None:
    """Extract one run into the dataset directory --out (its shard is replaced if it was extracted before)."""
    check_output(out, "dir")
    from uavcas.dataset.store import extract_run

    try:
        info = extract_run(run_dir, out, view=view, labels=labels, min_packets=min_packets, termination=termination,
                           allow_truncated=allow_truncated, features=features,
                           min_attack_fraction=min_attack_fraction, allow_incomplete=allow_incomplete)  # fmt: skip
    except _errors() as exc:
        raise fail(str(exc)) from None
    for t in info.truncations:
        err_console.print(f"[yellow]warning:[/] truncated capture {t}; kept the packets before it", highlight=False)
    if not info.complete:
        err_console.print(f"[yellow]warning:[/] run {info.run_id} is incomplete (exit status "
                          f"{info.run_exit_status}); its shard is marked so", highlight=False)
    counts = ", ".join(f"{k} {v}" for k, v in sorted(info.class_counts.items()))
    unit = "host-window rows" if info.view == EPISODE_VIEW else "flows"
    console.print(f"run [bold]{info.run_id}[/]: {info.n_flows} {unit} from {info.n_packets} packets ({counts}) -> {out}", highlight=False)
    if info.impure_dropped:
        console.print(f"{info.impure_dropped} flow(s) left out: attack_fraction below {min_attack_fraction:g}")


CSV_HELP = ("csv: one row per flow, CICIDS2017's column names (Flow ID, Source IP, .., Timestamp, the 47 features, "
            "the other columns, Label last; no seq_* lists); NaN and infinite values written as CICIDS2017's CSVs hold "
            "them, NaN / Infinity / -Infinity; other absent values (an import's ports) as empty fields.")


def export_cmd(
    dataset_dir: Path = dataset_argument(),
    fmt: one_of(EXPORT_FORMATS) = typer.Option("uavcas-csv", "--format", help="uavcas-csv: the authors' UAV-CAS_stat.csv + "
                                                                            "UAV-CAS_ts.csv, one row per host pair. " + CSV_HELP),
    out: Path = typer.Option(..., "--out", help="uavcas-csv: the directory to write the two files to; csv: the file."),
    embed_config: bool = typer.Option(False, "--embed-config", help="uavcas-csv: the _cfg variants, Label = <class>|<config>."),
    include_flags: bool = typer.Option(False, "--include-flags", help="uavcas-csv: add the packet_flag list column to the ts file."),
    view: View | None = typer.Option(None, "--view", help="The flow view to export when the dataset holds several."),
) -> None:
    """Export a dataset: in the authors' released layout (one stat and one ts CSV, one row per host
    pair: 5-tuple flows are merged into host pairs from their packet sequences), or as one plain
    CSV row per flow for CICIDS2017-style tooling (--format csv)."""
    from uavcas.dataset.parquet import read_flows
    from uavcas.dataset.read import select_view
    from uavcas.dataset.uavcas_csv import layout_rows, write_layout

    if fmt == "csv" and (embed_config or include_flags):
        raise fail(f"{'--embed-config' if embed_config else '--include-flags'}: applies to --format uavcas-csv only")
    check_output(out, "file" if fmt == "csv" else "dir")
    path = dataset_dir / "flows.parquet"
    if not path.is_file():
        raise fail(f"{dataset_dir}: no flows.parquet (not a dataset directory)")
    if fmt == "csv":
        from uavcas.dataset.cic_csv import write_flow_csv

        try:
            n = write_flow_csv(dataset_dir, out, view=view)
        except _errors() as exc:
            raise fail(str(exc)) from None
        console.print(f"wrote {out} ({n} flows)", highlight=False)
        return
    try:
        df = read_flows(path)  # write_layout creates --out once the rows are known (a refusal writes nothing)
        standard = df.attrs.get("feature_standard")
        df = select_view(df, view)
        df.attrs["feature_standard"] = standard
        df, merged = layout_rows(df)  # the authors' rows are host pairs
        w = write_layout(df, out, embed_config=embed_config, include_flags=include_flags)
    except _errors() as exc:
        raise fail(str(exc)) from None
    _warn(merged + w.notes)
    console.print(f"wrote {w.stat} ({w.n_stat} flows) and {w.ts} ({w.n_ts} flows)", highlight=False)


def import_cmd(
    src: Path = typer.Argument(..., help="Directory with UAV-CAS_stat.csv / UAV-CAS_ts.csv (or _cfg variants), or one of them."),
    fmt: one_of(IMPORT_FORMATS) = typer.Option("uavcas-csv", "--format", help="uavcas-csv: the authors' released layout."),
    out: Path = typer.Option(..., "--out", help="New dataset directory to create."),
) -> None:
    """Import the authors' CSV layout (theirs as released, or ours) into a dataset directory."""
    from uavcas.dataset.store import import_layout

    check_output(out, "dir")
    try:
        card, imp = import_layout(src, out)
    except _errors() as exc:
        raise fail(str(exc)) from None
    for note in imp.notes:
        console.print(note, highlight=False)
    err_console.print(f"the layout lacks: {', '.join(imp.lacks)}", highlight=False, soft_wrap=True)
    console.print(f"imported {card['n_flows']} flows ({card['features']['standard']} features) -> {out}", highlight=False)


def info_cmd(
    dataset_dir: Path = dataset_argument(),
    columns: bool = typer.Option(False, "--columns", help="List every column of flows.parquet with its dtype, unit "
                                                         "and meaning (tab-separated) instead."),
) -> None:
    """Class counts, feature standard, views, fidelity and the runs of a dataset (or its columns)."""
    from uavcas.dataset.runs import dataset_runs, percent
    from uavcas.dataset.store import card_standard, read_card

    try:
        card = read_card(dataset_dir)
    except _errors() as exc:
        raise fail(str(exc)) from None
    if columns:
        _print_columns(dataset_dir, card)
        return
    total = int(card.get("n_flows", 0))
    unit = "host-window rows" if card.get("unit") == "host-window" else "flows"
    table = Table(title=f"{dataset_dir}: {total} {unit}, {card.get('n_runs', 0)} runs")
    table.add_column("class")
    table.add_column("flows", justify="right")
    table.add_column("share", justify="right")
    for cls, n in card.get("class_counts", {}).items():
        table.add_row(cls, str(n), percent(n, total))
    std = card_standard(card)
    table.caption = (f"features: {std}; views: {', '.join(card.get('views', []))}; "
                     f"labels: {', '.join(card.get('label_modes', []))}; schema v{card.get('schema_version')}")  # fmt: skip
    console.print(table)
    runs = dataset_runs(dataset_dir, card)
    fid = card.get("fidelity") or {}
    console.print("fidelity: " + (", ".join(f"{n} {v}" for v, n in fid.items()) or "not recorded")
                  + f"; {sum(r.flagged for r in runs)} run(s) kept flagged", highlight=False, soft_wrap=True)
    per_run = Table(title="runs")
    for name, justify in (("run", "right"), ("config", "left"), (unit, "right"), ("classes", "left"),
                          ("fidelity", "left")):
        per_run.add_column(name, justify=justify, overflow="fold")
    for r in runs:
        per_run.add_row(r.run_id, r.config, str(r.rows),
                        ", ".join(f"{c} {n}" for c, n in r.classes.items()),
                        r.verdict + (f": {'; '.join(r.failed)}" if r.failed else ""))
    console.print(per_run)


def _print_columns(dataset_dir: Path, card: dict) -> None:
    """Every column of flows.parquet, from the data dictionary: name, dtype, unit, meaning (TSV)."""
    import pyarrow.parquet as pq

    from uavcas.dataset.dictionary import DictionaryError, columns
    from uavcas.dataset.store import card_standard

    path = Path(dataset_dir) / "flows.parquet"
    if not path.is_file():
        raise fail(f"{dataset_dir}: no flows.parquet beside dataset.json")
    try:
        cols = columns(pq.read_schema(path), card_standard(card),
                       episodes=card.get("unit") == "host-window")
    except DictionaryError as exc:
        raise fail(str(exc)) from None
    sys.stdout.write("column\tdtype\tunit\tmeaning\n")
    sys.stdout.write("".join(f"{c.name}\t{c.dtype}\t{c.unit}\t{c.meaning}\n" for c in cols))


def register(app: typer.Typer) -> None:
    app.command("flows")(flows_cmd)
    app.command("extract")(extract_cmd)
    app.command("export")(export_cmd)
    app.command("import")(import_cmd)
    app.command("info")(info_cmd)
