"""`uavcas flows | extract | export | info`: captures -> flows -> labeled dataset -> files."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import typer
from rich.table import Table

from .common import atomic_path, console, err_console, fail

TABLE_ROWS = 50  # the human-readable table shows this many flows; csv/parquet have them all


def _errors():
    from uavcas.dataset.external import ExternalFormatError
    from uavcas.dataset.store import DatasetError
    from uavcas.dataset.uavcas_csv import CsvFormatError
    from uavcas.flows import CaptureError
    from uavcas.labels import LabelError

    return (CaptureError, DatasetError, LabelError, CsvFormatError, ExternalFormatError, ValueError, OSError)


def _warn_truncations(truncations) -> None:
    for t in truncations:
        err_console.print(
            f"[yellow]warning:[/] {t.path} is truncated at byte offset {t.offset}; kept the packets before it",
            highlight=False,
            soft_wrap=True,
        )


def flows_cmd(
    pcaps: list[Path] = typer.Argument(..., help="Capture file(s), pcap or pcapng; several = capture points."),
    view: str = typer.Option("5tuple", "--view", help="Flow key: 5tuple or hostpair (the authors')."),
    min_packets: int = typer.Option(None, "--min-packets", help="Drop smaller flows (default 1 for 5tuple, 10 for hostpair)."),
    fmt: str = typer.Option("table", "--format", help="table, csv or parquet."),
    out: Path = typer.Option(None, "--out", help="Output file (default: standard output; required for parquet)."),
    allow_truncated: bool = typer.Option(False, "--allow-truncated", help="Keep the packets before a truncation."),
    idle_timeout: float = typer.Option(None, "--idle-timeout", help="Idle timeout in s (default: none)."),
    active_timeout: float = typer.Option(None, "--active-timeout", help="Active timeout in s (default: none)."),
) -> None:
    """Flows of one capture (or of several capture points, de-duplicated)."""
    from uavcas.flows import CSV_LEAD_COLUMNS, FlowConfig, extract_flows
    from uavcas.schema import FEATURES

    if fmt not in ("table", "csv", "parquet"):
        raise fail(f"--format: {fmt!r} is not one of table, csv, parquet")
    if fmt == "parquet" and out is None:
        raise fail("--format parquet needs --out FILE")
    try:
        cfg = FlowConfig(view=view, min_packets=min_packets, idle_timeout_s=idle_timeout, active_timeout_s=active_timeout)  # type: ignore[arg-type]
        ex = extract_flows(pcaps, cfg, allow_truncated=allow_truncated, sequences=fmt == "parquet")
    except _errors() as exc:
        raise fail(str(exc)) from None
    _warn_truncations(ex.packets.truncations)
    df = ex.frame
    if fmt == "parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq

        with atomic_path(out) as tmp:
            pq.write_table(pa.Table.from_pandas(df, preserve_index=False), tmp, compression="zstd")
        err_console.print(f"wrote {len(df)} flows to {out}", highlight=False)
        return
    if fmt == "csv":
        cols = list(CSV_LEAD_COLUMNS) + list(FEATURES) + ["first_ts", "last_ts", "capture_point"]
        text = df[cols].to_csv(index=False, float_format="%.9g")
        if out is None:
            sys.stdout.write(text)
        else:
            with atomic_path(out) as tmp:
                tmp.write_text(text)
        return
    table = Table(title=f"{len(df)} flows ({view}) from {len(ex.packets)} packets")
    for c in ("src", "dst", "proto", "packets", "bytes", "duration_s", "point"):
        table.add_column(c, justify="right" if c in ("packets", "bytes", "duration_s") else "left")
    for r in df.head(TABLE_ROWS).itertuples(index=False):
        table.add_row(
            f"{r.src_ip}:{r.src_port}", f"{r.dst_ip}:{r.dst_port}", str(r.protocol),
            str(r.packets), str(r.bytes), f"{r.duration_s:.6f}", str(r.capture_point),
        )  # fmt: skip
    if len(df) > TABLE_ROWS:
        table.caption = f"first {TABLE_ROWS} of {len(df)} flows; use --format csv for all"
    from rich.console import Console

    if out is None:  # addresses must not be cut: print wide even when stdout is not a terminal
        Console(width=max(console.width, 140)).print(table)
    else:
        buf = io.StringIO()
        Console(file=buf, width=160).print(table)
        with atomic_path(out) as tmp:
            tmp.write_text(buf.getvalue())


def extract_cmd(
    run_dir: Path = typer.Argument(..., help="Run directory (plan.json, run.json, attacks.jsonl, pcap/)."),
    out: Path = typer.Option(..., "--out", help="Dataset directory to add the run's shard to."),
    view: str = typer.Option("5tuple", "--view", help="Flow key: 5tuple or hostpair."),
    labels: str = typer.Option("ours", "--labels", help="ours (packet-exact / attack window) or paper (IP membership)."),
    min_packets: int = typer.Option(None, "--min-packets", help="Drop smaller flows (default by view)."),
    allow_truncated: bool = typer.Option(False, "--allow-truncated", help="Keep the packets before a truncation."),
    allow_incomplete: bool = typer.Option(False, "--allow-incomplete",
                                          help="Also extract a run that was killed or failed (marked incomplete)."),
) -> None:
    """Extract one run into DATASET_DIR (its shard is replaced if it was extracted before)."""
    from uavcas.dataset.store import extract_run

    try:
        info = extract_run(run_dir, out, view=view, labels=labels, min_packets=min_packets,
                           allow_truncated=allow_truncated, allow_incomplete=allow_incomplete)
    except _errors() as exc:
        raise fail(str(exc)) from None
    for t in info.truncations:
        err_console.print(f"[yellow]warning:[/] truncated capture {t}; kept the packets before it", highlight=False)
    if not info.complete:
        err_console.print(f"[yellow]warning:[/] run {info.run_id} is incomplete (exit status "
                          f"{info.run_exit_status}); its shard is marked so", highlight=False)
    counts = ", ".join(f"{k} {v}" for k, v in sorted(info.class_counts.items()))
    console.print(f"run [bold]{info.run_id}[/]: {info.n_flows} flows from {info.n_packets} packets ({counts}) -> {out}", highlight=False)


def export_cmd(
    dataset_dir: Path = typer.Argument(..., help="Dataset directory."),
    fmt: str = typer.Option("uavcas-csv", "--format", help="uavcas-csv (the authors' *_ts.csv + *_stat.csv)."),
    out: Path = typer.Option(..., "--out", help="Directory to write to."),
) -> None:
    """Export a dataset in the authors' CSV layout, one *_ts.csv / *_stat.csv pair per run."""
    from uavcas.dataset.parquet import read_flows
    from uavcas.dataset.uavcas_csv import write_uavcas_csv

    if fmt != "uavcas-csv":
        raise fail(f"--format: {fmt!r} is not supported (uavcas-csv)")
    path = dataset_dir / "flows.parquet"
    if not path.exists():
        raise fail(f"{dataset_dir}: no flows.parquet (not a dataset directory)")
    try:
        df = read_flows(path)
        n = 0
        for run_id, part in df.groupby("run_id", sort=True):
            write_uavcas_csv(part.reset_index(drop=True), out, str(run_id))
            n += 1
    except _errors() as exc:
        raise fail(str(exc)) from None
    console.print(f"wrote {n} run(s), {len(df)} flows to {out}", highlight=False)


def info_cmd(dataset_dir: Path = typer.Argument(..., help="Dataset directory.")) -> None:
    """Class counts, views and runs of a dataset."""
    from uavcas.dataset.store import read_card

    try:
        card = read_card(dataset_dir)
    except _errors() as exc:
        raise fail(str(exc)) from None
    total = max(int(card.get("n_flows", 0)), 1)
    table = Table(title=f"{dataset_dir}: {card.get('n_flows', 0)} flows, {card.get('n_runs', 0)} runs")
    table.add_column("class")
    table.add_column("flows", justify="right")
    table.add_column("share", justify="right")
    for cls, n in card.get("class_counts", {}).items():
        table.add_row(cls, str(n), f"{100.0 * n / total:.1f}%")
    table.caption = f"views: {', '.join(card.get('views', []))}; labels: {', '.join(card.get('label_modes', []))}; schema v{card.get('schema_version')}"
    console.print(table)


def register(app: typer.Typer) -> None:
    app.command("flows")(flows_cmd)
    app.command("extract")(extract_cmd)
    app.command("export")(export_cmd)
    app.command("info")(info_cmd)
