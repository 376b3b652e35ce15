"""A dataset directory: one Parquet shard per extracted run, their union, and a JSON card.

    DATASET_DIR/shards/<run_id>.parquet   one run (re-extracting the run replaces it)
    DATASET_DIR/flows.parquet             union of all shards, rewritten after every extract
    DATASET_DIR/dataset.json              schema version, feature standard, every column's
                                          dtype, unit and meaning (the data dictionary), views, flow rules, label modes
                                          and rules, class counts, packet effect counts, seeds,
                                          twin profiles (name + SHA-256), runs, library versions

Extraction itself is `uavcas.extract`. A run is identified by run.json's `run_id` when present,
else by the run directory's name; one shard per run id, so a run appears once whatever view or labels it was last
extracted with. Every file is written to a temporary name and renamed; concurrent extracts into the same
directory are serialised by an exclusive lock on DATASET_DIR/.lock.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from uavcas.atomic import atomic_write_text, ensure_out_dir
from uavcas.extract import ShardInfo, extract
from uavcas.flows.standards import DEFAULT_STANDARD
from uavcas.schema import CLASSES, EFFECTS, SCHEMA_VERSION
from uavcas.versions import package_versions
from uavcas.views import ViewSpec, recorded_view, view

from .dictionary import card_columns
from .parquet import META_KEY, table_meta, table_standard, with_dictionary, write_shard, write_table
from .uavcas_csv import Imported, read_layout

__all__ = ["DatasetError", "ShardInfo", "extract_run", "import_layout", "read_card", "rebuild"]


class DatasetError(ValueError):
    """A run or dataset directory that cannot be used; one-line message."""


def extract_run(run_dir: Path, out_dir: Path, **options: Any) -> ShardInfo:
    """`uavcas.extract.extract` one run (options: those of `uavcas.extract.extract_detailed`) into
    its shard; then flows.parquet and dataset.json are rebuilt.

    `run_id` overrides the run's own id (a campaign names runs by manifest index).
    """
    shard = extract(run_dir, **options)
    out_dir = ensure_out_dir(out_dir)  # only once there is a shard to write: bad input leaves nothing
    with _locked(out_dir):
        _check_unit(out_dir, shard.info.run_id, view(shard.info.view))
        write_shard(shard.frame, asdict(shard.info), out_dir / "shards" / f"{shard.info.run_id}.parquet")
        rebuild(out_dir)
    return shard.info


def _check_unit(out_dir: Path, run_id: str, spec: ViewSpec) -> None:
    """Refuse, before anything is written, a shard whose rows are of another unit than the
    dataset's (flows among window-host rows, or the reverse)."""
    for path in sorted((out_dir / "shards").glob("*.parquet")):
        have = recorded_view(table_meta(path))
        if path.stem != run_id and have.unit != spec.unit:
            raise DatasetError(f"{out_dir}: holds {have.row.plural} ({have.name}); a dataset holds one kind of row, "
                               f"not {spec.row.plural} too: extract the {spec.name} view into another --out")


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
    standards = sorted({table_standard(t) for t in tables})
    if len(standards) > 1:
        raise DatasetError(f"{out_dir}: shards of different feature standards {standards}; extract every run with one "
                           "--features")
    standard = standards[0]
    runs = [table_meta(s) for s in shards]
    # the units of rows (flows, window-host rows) have different columns: one per dataset
    spec = recorded_view(runs[0])
    other = next((v for v in map(recorded_view, runs) if v.unit != spec.unit), None)
    if other is not None:
        raise DatasetError(f"{out_dir}: holds {spec.row.plural} and {other.row.plural} shards; a dataset holds one "
                           f"kind of row: extract the {other.name} view into another --out")
    # a view without context columns has none to check
    with_ctx = {bool(spec.context_columns) and t.schema.get_field_index(spec.context_columns[0]) >= 0 for t in tables}
    if len(with_ctx) > 1:
        raise DatasetError(f"{out_dir}: some shards have the context columns (ctx_*) and some do not; "
                           "extract every run with the same uavcas version")
    union = with_dictionary(pa.concat_tables([t.replace_schema_metadata(None) for t in tables]), standard, spec)
    write_table(union.replace_schema_metadata({META_KEY: json.dumps({"feature_standard": standard}).encode()}),
                out_dir / "flows.parquet")
    counts: dict[str, int] = {c: 0 for c in CLASSES}
    vc = pc.value_counts(union.column("label")).to_pylist() if union.num_rows else []
    for item in vc:
        counts[item["values"]] = counts.get(item["values"], 0) + int(item["counts"])
    card = {
        "schema_version": SCHEMA_VERSION,
        "features": dict(spec.feature_card(standard)),
        # every column of flows.parquet: dtype, unit, meaning (uavcas.dataset.dictionary)
        "columns": card_columns(union.schema, standard, spec),
        # what a row is (the view's unit): a flow, or (window-host) one plan node's traffic in one plan window
        "unit": spec.unit,
        # the ctx_* columns (uavcas.flows.context) and their window, null when the shards lack them
        "context": {"columns": len(spec.context_columns),
                    "window_s": runs[0].get("context_window_s")} if with_ctx == {True} else None,
        "n_flows": union.num_rows,
        "n_runs": len(shards),
        "n_incomplete_runs": sum(1 for r in runs if r.get("complete") is False),
        "views": sorted({r.get("view") for r in runs if r.get("view")}),
        # how flows end (uavcas.flows.termination): connection, cic or timeout
        "terminations": sorted({(r.get("flow_rules") or {}).get("termination") for r in runs} - {None}),
        "label_modes": sorted({r.get("labels") for r in runs if r.get("labels")}),
        "class_counts": counts,
        # How flows got their labels: one rule text per (label mode, min_attack_fraction) in use.
        "label_rules": sorted({r["label_rule"] for r in runs if r.get("label_rule")}),
        "effect_counts": _effect_counts(runs),
        "seeds": sorted({int(r["seed"]) for r in runs if "seed" in r}),
        # Twin profiles the runs were planned with: name -> the SHA-256s of their JSON.
        "profiles": {name: sorted({r.get("profile_sha256") for r in runs if r.get("profile") == name} - {None})
                     for name in sorted({r["profile"] for r in runs if r.get("profile")})},
        # runs by fidelity verdict (uavcas.fidelity): how many failed their audit
        "fidelity": {v: sum(1 for r in runs if (r.get("fidelity") or "unaudited") == v)
                     for v in ("pass", "fail", "error", "unaudited")},
        # runs whose MAVLink was signed (MAVLink 2 signing, `uavcas run --mavlink-signing`) or not
        "mavlink_signing": {k: sum(1 for r in runs if r.get("mavlink_signing") is v)
                            for k, v in (("on", True), ("off", False), ("unknown", None))},
        "runs": runs,
        "versions": package_versions("numpy", "pandas", "pyarrow"),
    }
    atomic_write_text(out_dir / "dataset.json", json.dumps(card, indent=1, sort_keys=False) + "\n")
    return card


def _effect_counts(runs: list[dict]) -> dict[str, int]:
    """Captured packet observations per effect, summed over the runs."""
    out = {e: 0 for e in EFFECTS}
    for r in runs:
        for e, n in (r.get("effect_counts") or {}).items():
            out[e] = out.get(e, 0) + int(n)
    return out


def card_standard(card: dict) -> str:
    """The feature standard a card names (cards before standards were recorded: the default)."""
    return (card.get("features") or {}).get("standard", DEFAULT_STANDARD)


def read_card(dataset_dir: Path) -> dict:
    path = Path(dataset_dir) / "dataset.json"
    if not Path(dataset_dir).exists():
        raise DatasetError(f"{dataset_dir} does not exist")
    if not path.exists():
        raise DatasetError(f"{dataset_dir}: no dataset.json (not a dataset directory)")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{path}: not JSON ({exc.msg})") from None


def import_layout(src: Path, out_dir: Path) -> tuple[dict, "Imported"]:
    """Read the authors' CSV layout at `src` into a new dataset directory `out_dir`.

    `out_dir` must not hold a dataset already (nothing the tool did not create is replaced). The
    flows become one shard, `shards/import.parquet`, whose metadata (and so the card's `runs`)
    records the files read and what the layout lacks.
    """
    out_dir = ensure_out_dir(out_dir)
    if any(out_dir.iterdir()):
        raise DatasetError(f"{out_dir}: not empty; import into a new directory")
    imp = read_layout(Path(src))
    meta = {"run_id": "import", "source": "uavcas-csv", "files": imp.files, "lacks": imp.lacks, "notes": imp.notes,
            "features": imp.standard}
    with _locked(out_dir):
        write_shard(imp.frame, meta, out_dir / "shards" / "import.parquet")
        card = rebuild(out_dir)
    return card, imp
