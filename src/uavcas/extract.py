"""The extraction stage: `extract(run_dir) -> Shard`, one run's labelled flows with their axes.

Captures -> flows (`uavcas.flows`) -> ground-truth labels (`uavcas.labels`) -> identity and axis
columns from the plan's typed scenario (nothing here parses the config string). Writing the shard
and the dataset card is `uavcas.dataset.store`'s job.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from uavcas.flows import FlowConfig, extract_flows
from uavcas.labels import label_flows, read_attack_log
from uavcas.rundir import RunDir, RunDirError
from uavcas.schema import DEFAULT_STANDARD


@dataclass(frozen=True)
class ShardInfo:
    run_id: str
    config: str
    seed: int
    view: str
    labels: str
    features: str
    flow_rules: dict
    min_packets: int
    n_packets: int
    n_flows: int
    class_counts: dict[str, int]
    truncations: list[str]
    extracted_unix: float


@dataclass(frozen=True)
class Shard:
    frame: pd.DataFrame  # schema.METADATA_COLUMNS + features, one row per flow
    info: ShardInfo


def _check_run_id(run_dir: Path, rid: str) -> str:
    if not rid or "/" in rid or rid.startswith("."):
        raise RunDirError(f"{run_dir}: unusable run id {rid!r}")
    return rid


def extract(
    run_dir: Path | str,
    view: str = "5tuple",
    labels: str = "ours",
    min_packets: int | None = None,
    allow_truncated: bool = False,
    run_id: str | None = None,
    features: str = DEFAULT_STANDARD,
) -> Shard:
    """Flows + labels of one run. The run id is `run_id`, else run.json's, else the dir's name."""
    rd = RunDir(Path(run_dir))
    if not rd.root.is_dir():
        raise RunDirError(f"{rd.root}: not a directory")
    plan = rd.read_plan()
    if plan.scenario is None:
        raise RunDirError(f"{rd.plan_json}: config {plan.config!r} is no scenario (no axes to record)")
    info = rd.read_info()
    pcaps = rd.pcaps()
    if not pcaps:
        raise RunDirError(f"{rd.root}: no captures in {rd.pcap_dir}")
    cfg = FlowConfig(view=view, min_packets=min_packets)  # type: ignore[arg-type]
    ex = extract_flows(pcaps, cfg, points=[p.stem for p in pcaps], allow_truncated=allow_truncated, standard=features)
    t0 = info.t0_unix if info else None
    log = read_attack_log(rd.attacks_jsonl, plan, t0)
    df = label_flows(ex.packets, ex.flows, ex.frame, log, mode=labels)  # type: ignore[arg-type]
    rid = _check_run_id(rd.root, str(run_id or (info.run_id if info else None) or rd.root.resolve().name))
    df["run_id"], df["config"], df["seed"], df["view"] = rid, plan.config, plan.seed, view
    for k, v in plan.scenario.axes().items():
        df[k] = v
    counts = {str(k): int(v) for k, v in df["label"].value_counts().items()}
    return Shard(
        frame=df,
        info=ShardInfo(
            run_id=rid,
            config=plan.config,
            seed=plan.seed,
            view=view,
            labels=labels,
            features=features,
            flow_rules=cfg.describe(),
            min_packets=cfg.effective_min_packets,
            n_packets=len(ex.packets),
            n_flows=len(df),
            class_counts=counts,
            truncations=[f"{t.path}@{t.offset}" for t in ex.packets.truncations],
            extracted_unix=time.time(),
        ),
    )
