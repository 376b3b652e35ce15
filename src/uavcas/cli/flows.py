"""`uavcas flows PCAP...`: the flows of captures, as a table, CSV or Parquet (`uavcas.flows`;
the files are written by `uavcas.dataset.flow_files`)."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import pandas as pd
import typer
from rich.console import Console
from rich.table import Table

from uavcas.dataset.flow_files import write_csv, write_parquet
from uavcas.flows import FlowConfig, StreamReport, iter_flow_frames

from .common import (
    Standard,
    Termination,
    View,
    allow_truncated_option,
    atomic_write_text,
    check_output,
    console,
    dataset_errors,
    err_console,
    fail,
    features_option,
    one_of,
    termination_option,
    warn,
)

FlowsFormat = one_of(("table", "csv", "parquet"))

TABLE_ROWS = 50  # the human-readable table shows this many flows; csv/parquet have them all


def _report_warnings(report) -> None:
    warn(f"{t.path} is truncated at byte offset {t.offset}; kept the packets before it" for t in report.truncations)
    for st in report.stats:
        warn(st.warnings())


def flows_cmd(
    pcaps: list[Path] = typer.Argument(..., help="Capture file(s), pcap or pcapng; several = capture points."),
    view: View = typer.Option("5tuple", "--view", help="Flow key: 5tuple or hostpair (the authors')."),
    features: Standard = features_option(),
    min_packets: int = typer.Option(None, "--min-packets",
                                    help="Drop smaller flows (default 1 for 5tuple, 2 under --termination cic, 10 for "
                                         "hostpair)."),
    fmt: FlowsFormat = typer.Option("table", "--format", help="table, csv or parquet."),
    out: Path = typer.Option(None, "--out", help="Output file (default: standard output; required for parquet)."),
    allow_truncated: bool = allow_truncated_option(),
    termination: Termination | None = termination_option(),
    idle_timeout: float = typer.Option(None, "--idle-timeout",
                                       help="Idle timeout in s; 0 = none (default: connection 15, cic none, timeout "
                                            "120)."),
    active_timeout: float = typer.Option(None, "--active-timeout",
                                         help="Active timeout in s; 0 = none (default: connection and cic 120, timeout "
                                              "1800)."),
    close_grace: float = typer.Option(None, "--close-grace",
                                      help="connection: s after a close during which the connection's packets join it "
                                           "(default 60)."),
) -> None:
    """Flows of one capture (streamed, bounded memory) or of several capture points (de-duplicated)."""
    if fmt == "parquet" and out is None:
        raise fail("--format parquet needs --out FILE")
    if out is not None:
        check_output(out, "file")
    report = StreamReport()
    try:
        cfg = FlowConfig(view=view, termination=termination, min_packets=min_packets, idle_timeout_s=idle_timeout,  # type: ignore[arg-type]
                         active_timeout_s=active_timeout, grace_s=close_grace)  # fmt: skip
        frames = iter_flow_frames(pcaps, cfg, standard=features, sequences=fmt == "parquet",
                                  allow_truncated=allow_truncated, report=report)  # fmt: skip
        if fmt == "parquet":
            write_parquet(frames, out, features)
            _report_warnings(report)
            err_console.print(f"wrote {report.flows} flows to {out}", highlight=False)
            return
        if fmt == "csv":
            if out is None:
                sys.stdout.flush()
                write_csv(frames, sys.stdout.buffer, features)
                sys.stdout.buffer.flush()
            else:
                write_csv(frames, out, features)
            _report_warnings(report)
            return
        shown = []
        for df in frames:  # read to the end: the title counts every flow
            if sum(len(d) for d in shown) < TABLE_ROWS:
                shown.append(df.head(TABLE_ROWS))
    except dataset_errors() as exc:
        raise fail(str(exc)) from None
    _report_warnings(report)
    _print_table(shown, view, report, out)


def _print_table(shown: list, view: str, report, out: Path | None) -> None:


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
    if out is None:  # addresses must not be cut: print wide even when stdout is not a terminal
        Console(width=max(console.width, 140)).print(table)
        return
    buf = io.StringIO()
    Console(file=buf, width=160).print(table)
    try:
        atomic_write_text(out, buf.getvalue())
    except dataset_errors() as exc:
        raise fail(str(exc)) from None


def register(app: typer.Typer) -> None:
    app.command("flows")(flows_cmd)
