"""A dataset directory: one Parquet shard per extracted run, their union, and a JSON card.

    DATASET_DIR/shards/<run_id>.parquet   one run (re-extracting the run replaces it)
    DATASET_DIR/flows.parquet             union of all shards, rewritten after every extract
    DATASET_DIR/dataset.json              schema version, views, label modes, class counts,
                                          seeds, runs, library versions

Extraction itself is `uavcas.extract`. A run is identified by run.json's `run_id` when present,
else by the run directory's name; one shard per run id, so a run appears once whatever view or labels it was last extracted with.
Every file is written to a temporary name and renamed; concurrent extracts into the same
directory are serialised by an exclusive lock on DATASET_DIR/.lock.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
from dataclasses import asdict
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from uavcas.atomic import atomic_write_text
from uavcas.extract import ShardInfo, extract
from uavcas.schema import CLASSES, SCHEMA_VERSION
from uavcas.versions import package_versions

from .parquet import to_table, table_meta, write_table

__all__ = ["DatasetError", "ShardInfo", "extract_run", "read_card", "rebuild"]


class DatasetError(ValueError):
    """A run or dataset directory that cannot be used; one-line message."""


def extract_run(
    run_dir: Path,
    out_dir: Path,
    view: str = "5tuple",
    labels: str = "ours",
    min_packets: int | None = None,
    allow_truncated: bool = False,
    run_id: str | None = None,
    allow_incomplete: bool = False,
) -> ShardInfo:
    """`uavcas.extract.extract` one run into its shard; then flows.parquet and dataset.json are rebuilt.

    `run_id` overrides the run's own id (a campaign names runs by manifest index).
    """
    shard = extract(run_dir, view=view, labels=labels, min_packets=min_packets,
                    allow_truncated=allow_truncated, run_id=run_id, allow_incomplete=allow_incomplete)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with _locked(out_dir):
        write_table(to_table(shard.frame, meta=asdict(shard.info)), out_dir / "shards" / f"{shard.info.run_id}.parquet")
        rebuild(out_dir)
    return shard.info


@contextlib.contextmanager
def _locked(out_dir: Path):
    with open(out_dir / ".lock", "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def rebuild(out_dir: Path) -> dict:
    """Rewrite flows.parquet (union of the shards, sorted by run id) and dataset.json."""
    shards = sorted((out_dir / "shards").glob("*.parquet"))
    if not shards:
        raise DatasetError(f"{out_dir}: no shards")
    tables = [pq.read_table(s) for s in shards]
    union = pa.concat_tables([t.replace_schema_metadata(None) for t in tables])
    write_table(union, out_dir / "flows.parquet")
    runs = [table_meta(s) for s in shards]
    counts: dict[str, int] = {c: 0 for c in CLASSES}
    vc = pc.value_counts(union.column("label")).to_pylist() if union.num_rows else []
    for item in vc:
        counts[item["values"]] = counts.get(item["values"], 0) + int(item["counts"])
    card = {
        "schema_version": SCHEMA_VERSION,
        "n_flows": union.num_rows,
        "n_runs": len(shards),
        "n_incomplete_runs": sum(1 for r in runs if r.get("complete") is False),
        "views": sorted({r.get("view") for r in runs if r.get("view")}),
        "label_modes": sorted({r.get("labels") for r in runs if r.get("labels")}),
        "class_counts": counts,
        "seeds": sorted({int(r["seed"]) for r in runs if "seed" in r}),
        "runs": runs,
        "versions": package_versions("numpy", "pandas", "pyarrow"),
    }
    atomic_write_text(out_dir / "dataset.json", json.dumps(card, indent=1, sort_keys=False) + "\n")
    return card


def read_card(dataset_dir: Path) -> dict:
    path = Path(dataset_dir) / "dataset.json"
    if not path.exists():
        raise DatasetError(f"{dataset_dir}: no dataset.json (not a dataset directory)")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{path}: not JSON ({exc.msg})") from None
