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
from uavcas.flows.standards import standard as feature_standard
from uavcas.schema import (
    CLASSES,
    CONTEXT_FEATURES,
    EFFECTS,
    EPISODE_CONTEXT_FEATURES,
    EPISODE_VIEW,
    SCHEMA_VERSION,
)
from uavcas.versions import package_versions

from .dictionary import card_columns
from .parquet import META_KEY, table_meta, table_standard, to_table, with_dictionary, write_table
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
        _check_unit(out_dir, shard.info.run_id, episodes="host" in shard.frame.columns)
        write_table(to_table(shard.frame, meta=asdict(shard.info), standard=shard.info.features),
                    out_dir / "shards" / f"{shard.info.run_id}.parquet")
        rebuild(out_dir)
    return shard.info


def _check_unit(out_dir: Path, run_id: str, episodes: bool) -> None:
    """Refuse, before anything is written, a shard of flows among episode shards or the reverse."""
    for path in sorted((out_dir / "shards").glob("*.parquet")):
        if path.stem != run_id and (pq.read_schema(path).get_field_index("host") >= 0) != episodes:
            raise DatasetError(f"{out_dir}: holds {'flow' if episodes else EPISODE_VIEW} shards; a dataset holds flows "
                               f"or {EPISODE_VIEW} episodes, not both: extract into another --out")


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
    # episodes (window-host) and flows are different units with different columns: one per dataset
    episodes = {t.schema.get_field_index("host") >= 0 for t in tables}
    if len(episodes) > 1:
        raise DatasetError(f"{out_dir}: holds flow shards, and a {EPISODE_VIEW} shard would mix episodes with flows; "
                           f"extract the {EPISODE_VIEW} view into another --out")
    episode = episodes == {True}
    with_ctx = {t.schema.get_field_index((EPISODE_CONTEXT_FEATURES if episode else CONTEXT_FEATURES)[0]) >= 0
                for t in tables}
    if len(with_ctx) > 1:
        raise DatasetError(f"{out_dir}: some shards have the context columns (ctx_*) and some do not; "
                           "extract every run with the same uavcas version")
    union = with_dictionary(pa.concat_tables([t.replace_schema_metadata(None) for t in tables]), standard)
    write_table(union.replace_schema_metadata({META_KEY: json.dumps({"feature_standard": standard}).encode()}),
                out_dir / "flows.parquet")
    runs = [table_meta(s) for s in shards]
    counts: dict[str, int] = {c: 0 for c in CLASSES}
    vc = pc.value_counts(union.column("label")).to_pylist() if union.num_rows else []
    for item in vc:
        counts[item["values"]] = counts.get(item["values"], 0) + int(item["counts"])
    card = {
        "schema_version": SCHEMA_VERSION,
        "features": feature_card(standard, episodes=episode),
        # every column of flows.parquet: dtype, unit, meaning (uavcas.dataset.dictionary)
        "columns": card_columns(union.schema, standard, episodes=episode),
        # what a row is: a flow, or (window-host) one plan node's traffic in one plan window
        "unit": "host-window" if episode else "flow",
        # the ctx_* columns (uavcas.flows.context) and their window, null when the shards lack them
        "context": {"columns": len(EPISODE_CONTEXT_FEATURES if episode else CONTEXT_FEATURES),
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


def feature_card(standard: str, episodes: bool = False) -> dict:
    """The card's record of a feature standard: its name, source and the unit of every column,
    all from the standard's module (`uavcas.flows.standards`).

    `episodes`: the window-host view's columns instead (`uavcas.labels.episodes`): packet counts
    and the mean / max of a subset of the standard's flow features (units of those features)."""
    std = feature_standard(standard)
    source = f"{std.source} ({std.module})"
    if not episodes:
        return {"standard": std.name, "source": source, "units": dict(std.units)}
    return {"standard": std.name, "source": f"{EPISODE_VIEW} episodes (uavcas.labels.episodes) of flows by {source}",
            "summarised": {stem: feat for feat, stem in std.episode_summary.items()}, "units": std.episode_units}


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
    meta = {"run_id": "import", "source": "uavcas-csv", "files": imp.files, "lacks": imp.lacks, "notes": imp.notes}
    with _locked(out_dir):
        write_table(to_table(imp.frame, meta=meta), out_dir / "shards" / "import.parquet")
        card = rebuild(out_dir)
    return card, imp
