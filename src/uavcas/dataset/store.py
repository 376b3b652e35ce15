"""A dataset directory: one Parquet shard per extracted run, their union, and a JSON card.

    DATASET_DIR/shards/<run_id>.parquet   one run (re-extracting the run replaces it)
    DATASET_DIR/flows.parquet             union of all shards, rewritten after every extract
    DATASET_DIR/dataset.json              schema version, views, label modes, class counts,
                                          seeds, runs, library versions

A run is identified by run.json's `run_id` when present, else by the run directory's name; one
shard per run id, so a run appears once whatever view or labels it was last extracted with.
Every file is written to a temporary name and renamed; concurrent extracts into the same
directory are serialised by an exclusive lock on DATASET_DIR/.lock.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from uavcas import __version__
from uavcas.atomic import atomic_write_text
from uavcas.flows import FlowConfig, extract_flows
from uavcas.labels import label_flows, read_attack_log
from uavcas.scenario.codec import Scenario
from uavcas.twin.model import Plan

from .parquet import to_table, table_meta, write_table
from .schema import CLASSES, SCHEMA_VERSION

CAPTURE_SUFFIXES = (".pcap", ".pcapng")


class DatasetError(ValueError):
    """A run or dataset directory that cannot be used; one-line message."""


@dataclass(frozen=True)
class ShardInfo:
    run_id: str
    config: str
    seed: int
    view: str
    labels: str
    min_packets: int
    n_packets: int
    n_flows: int
    class_counts: dict[str, int]
    truncations: list[str]
    extracted_unix: float


def _run_id(run_dir: Path, run_json: dict) -> str:
    rid = str(run_json.get("run_id") or run_dir.resolve().name)
    if not rid or "/" in rid or rid.startswith("."):
        raise DatasetError(f"{run_dir}: unusable run id {rid!r}")
    return rid


def load_run(run_dir: Path) -> tuple[Plan, dict, list[Path]]:
    """plan.json, run.json (may be absent: {}) and the capture files of a run directory."""
    if not run_dir.is_dir():
        raise DatasetError(f"{run_dir}: not a directory")
    plan_path = run_dir / "plan.json"
    if not plan_path.exists():
        raise DatasetError(f"{run_dir}: no plan.json (not a run directory)")
    try:
        plan = Plan.from_json(plan_path.read_text())
    except ValueError as exc:
        raise DatasetError(f"{plan_path}: invalid plan ({str(exc).splitlines()[0]})") from None
    run_json: dict = {}
    if (run_dir / "run.json").exists():
        try:
            run_json = json.loads((run_dir / "run.json").read_text())
        except json.JSONDecodeError as exc:
            raise DatasetError(f"{run_dir / 'run.json'}: not JSON ({exc.msg})") from None
    pcaps = sorted(p for p in (run_dir / "pcap").glob("*") if p.suffix in CAPTURE_SUFFIXES)
    if not pcaps:
        raise DatasetError(f"{run_dir}: no captures in {run_dir / 'pcap'}")
    return plan, run_json, pcaps


def extract_run(
    run_dir: Path,
    out_dir: Path,
    view: str = "5tuple",
    labels: str = "ours",
    min_packets: int | None = None,
    allow_truncated: bool = False,
    run_id: str | None = None,
) -> ShardInfo:
    """Flows + labels of one run -> its shard; then flows.parquet and dataset.json are rebuilt.

    `run_id` overrides the run's own id (a campaign names runs by manifest index).
    """
    run_dir, out_dir = Path(run_dir), Path(out_dir)
    plan, run_json, pcaps = load_run(run_dir)
    cfg = FlowConfig(view=view, min_packets=min_packets)  # type: ignore[arg-type]
    ex = extract_flows(pcaps, cfg, points=[p.stem for p in pcaps], allow_truncated=allow_truncated)
    t0 = run_json.get("t0_unix")
    log = read_attack_log(run_dir / "attacks.jsonl", plan, None if t0 is None else float(t0))
    df = label_flows(ex.packets, ex.flows, ex.frame, log, mode=labels)  # type: ignore[arg-type]
    run_id = _run_id(run_dir, {"run_id": run_id} if run_id else run_json)
    df["run_id"], df["config"], df["seed"], df["view"] = run_id, plan.config, plan.seed, view
    for k, v in Scenario.parse(plan.config).axes().items():
        df[k] = v
    counts = {str(k): int(v) for k, v in df["label"].value_counts().items()}
    info = ShardInfo(
        run_id=run_id,
        config=plan.config,
        seed=plan.seed,
        view=view,
        labels=labels,
        min_packets=cfg.effective_min_packets,
        n_packets=len(ex.packets),
        n_flows=len(df),
        class_counts=counts,
        truncations=[f"{t.path}@{t.offset}" for t in ex.packets.truncations],
        extracted_unix=time.time(),
    )
    out_dir.mkdir(parents=True, exist_ok=True)
    with _locked(out_dir):
        write_table(to_table(df, meta=asdict(info)), out_dir / "shards" / f"{run_id}.parquet")
        rebuild(out_dir)
    return info


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
        "views": sorted({r.get("view") for r in runs if r.get("view")}),
        "label_modes": sorted({r.get("labels") for r in runs if r.get("labels")}),
        "class_counts": counts,
        "seeds": sorted({int(r["seed"]) for r in runs if "seed" in r}),
        "runs": runs,
        "versions": _versions(),
    }
    atomic_write_text(out_dir / "dataset.json", json.dumps(card, indent=1, sort_keys=False) + "\n")
    return card


def _versions() -> dict[str, str]:
    import numpy
    import pandas

    return {"uavcas": __version__, "numpy": numpy.__version__, "pandas": pandas.__version__, "pyarrow": pa.__version__}


def read_card(dataset_dir: Path) -> dict:
    path = Path(dataset_dir) / "dataset.json"
    if not path.exists():
        raise DatasetError(f"{dataset_dir}: no dataset.json (not a dataset directory)")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{path}: not JSON ({exc.msg})") from None
