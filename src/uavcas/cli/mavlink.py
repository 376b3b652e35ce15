"""`uavcas mavlink RUN_DIR`: every MAVLink message in a run's captures, with its packet's truth."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import typer
from rich.console import Console
from rich.table import Table

from uavcas.mavlink_capture import TABLE_SUFFIXES, mavlink_table, problems, write_table

from .common import allow_truncated_option, check_output, console, err_console, fail, run_dir_argument, warn

TABLE_ROWS = 50  # the terminal table shows this many messages; --out has them all


def mavlink_cmd(
    run_dir: Path = run_dir_argument(),
    out: Path = typer.Option(None, "--out", help="Write the whole table: FILE.parquet or FILE.csv (by suffix)."),
    port: int = typer.Option(14550, "--port", help="UDP port of the MAVLink datagrams (source or destination)."),
    point: str = typer.Option(None, "--point", help="Keep one capture point (e.g. s-uav0). Without it a packet "
                                                    "seen at k switches lists its messages k times, once per point."),
    dialect: str = typer.Option("ardupilotmega", "--dialect", help="pymavlink dialect (pymavlink.dialects.v20)."),
    allow_truncated: bool = allow_truncated_option(),
) -> None:
    """Decode every MAVLink message of a run's captures: one row per message and capture point, with
    time, addresses, header, fields (JSON and position columns in the message's units), CRC check,
    a position report's offset from the plan's track (claimed minus true, metres east/north/up: a
    spoofed GPS's drift) and the packet's effect and family from the ground truth."""
    if out is not None and out.suffix.lower() not in TABLE_SUFFIXES:
        raise fail(f"--out: {out} must end in {' or '.join(TABLE_SUFFIXES)}")
    if out is not None:
        check_output(out, "file")
    try:
        df = mavlink_table(run_dir, port=port, point=point, dialect=dialect, allow_truncated=allow_truncated)
        if out is not None:
            write_table(df, out)
    except (ValueError, OSError) as exc:  # RunDirError, LabelError, CaptureError, MavlinkError: one line
        raise fail(str(exc).splitlines()[0] if str(exc) else type(exc).__name__) from None
    warn(problems(df))
    if out is not None:
        err_console.print(f"wrote {len(df)} MAVLink rows to {out}", highlight=False)
        return
    _print(df, point)


def _print(df, point: str | None) -> None:
    where = f"at {point}" if point else "over all capture points (one row per observation)"
    table = Table(title=f"{len(df)} MAVLink rows {where}")
    for c in ("ts_s", "point", "src", "dst", "sysid", "compid", "seq", "msg_name", "crc_ok", "offset e/n/u m",
              "effect"):
        table.add_column(c, justify="right" if c in ("sysid", "compid", "seq", "offset e/n/u m") else "left")
    na = lambda v: "-" if pd.isna(v) else str(v)  # noqa: E731  (None, NaN and pd.NA alike)
    for r in df.head(TABLE_ROWS).itertuples(index=False):
        off = "-" if pd.isna(r.offset_east_m) else f"{r.offset_east_m:.2f}/{r.offset_north_m:.2f}/{r.offset_up_m:.2f}"
        table.add_row(f"{r.ts_s:.6f}", str(r.point), f"{r.src_ip}:{r.src_port}", f"{r.dst_ip}:{r.dst_port}",
                      na(r.sysid), na(r.compid), na(r.seq), na(r.msg_name), na(r.crc_ok), off, str(r.effect))
    if len(df) > TABLE_ROWS:
        table.caption = f"first {TABLE_ROWS} of {len(df)} rows; use --out FILE.parquet for all"
    wide = Console(width=max(console.width, 140))  # addresses must not be cut
    wide.print(table)
    counts = Table(title="messages per name")
    counts.add_column("msg_name")
    counts.add_column("rows", justify="right")
    counts.add_column("crc_ok", justify="right")
    names = df["msg_name"].fillna("(no MAVLink frame)")
    ok = df["crc_ok"].fillna(False).astype(bool)
    for name, n in names.value_counts().sort_index().items():
        counts.add_row(str(name), str(int(n)), str(int(ok[names == name].sum())))
    wide.print(counts)


def register(app: typer.Typer) -> None:
    app.command("mavlink")(mavlink_cmd)
