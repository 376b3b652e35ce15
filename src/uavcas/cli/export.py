"""`uavcas export DATASET --out ...`: a dataset in the authors' CSV layout (`uavcas.dataset.uavcas_csv`)
or as one CSV row per flow (`uavcas.dataset.cic_csv`)."""

from __future__ import annotations

from pathlib import Path

import typer

from uavcas.dataset.cic_csv import write_flow_csv
from uavcas.dataset.parquet import read_flows
from uavcas.dataset.read import EXPORT_FORMATS, select_view
from uavcas.dataset.uavcas_csv import layout_rows, write_layout

from .common import View, check_output, console, dataset_argument, dataset_errors, fail, one_of, warn

CSV_HELP = ("csv: one row per flow, CICIDS2017's column names (Flow ID, Source IP, .., Timestamp, the 47 features, "
            "the other columns, Label last; no seq_* lists); NaN and infinite values written as CICIDS2017's CSVs hold "
            "them, NaN / Infinity / -Infinity; other absent values (an import's ports) as empty fields.")


def export_cmd(
    dataset_dir: Path = dataset_argument(),
    fmt: one_of(EXPORT_FORMATS) = typer.Option("uavcas-csv", "--format",
                                               help="uavcas-csv: the authors' UAV-CAS_stat.csv + UAV-CAS_ts.csv, "
                                                    "one row per host pair. " + CSV_HELP),
    out: Path = typer.Option(..., "--out", help="uavcas-csv: the directory to write the two files to; csv: the file."),
    embed_config: bool = typer.Option(False, "--embed-config",
                                      help="uavcas-csv: the _cfg variants, Label = <class>|<config>."),
    include_flags: bool = typer.Option(False, "--include-flags",
                                       help="uavcas-csv: add the packet_flag list column to the ts file."),
    view: View | None = typer.Option(None, "--view", help="The flow view to export when the dataset holds several."),
) -> None:
    """Export a dataset: in the authors' released layout (one stat and one ts CSV, one row per host
    pair: 5-tuple flows are merged into host pairs from their packet sequences), or as one plain
    CSV row per flow for CICIDS2017-style tooling (--format csv)."""
    if fmt == "csv" and (embed_config or include_flags):
        raise fail(f"{'--embed-config' if embed_config else '--include-flags'}: applies to --format uavcas-csv only")
    check_output(out, "file" if fmt == "csv" else "dir")
    path = dataset_dir / "flows.parquet"
    if not path.is_file():
        raise fail(f"{dataset_dir}: no flows.parquet (not a dataset directory)")
    if fmt == "csv":
        try:
            n = write_flow_csv(dataset_dir, out, view=view)
        except dataset_errors() as exc:
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
    except dataset_errors() as exc:
        raise fail(str(exc)) from None
    warn(merged + w.notes)
    console.print(f"wrote {w.stat} ({w.n_stat} flows) and {w.ts} ({w.n_ts} flows)", highlight=False)


def register(app: typer.Typer) -> None:
    app.command("export")(export_cmd)
