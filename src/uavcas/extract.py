"""The extraction stage: `extract(run_dir) -> Shard`, one run's labelled flows with their axes.

Captures -> flows (`uavcas.flows`) -> ground-truth labels (`uavcas.labels`) -> identity and axis
columns from the plan's typed scenario (nothing here parses the config string). Writing the shard
and the dataset card is `uavcas.dataset.store`'s job.

Only complete runs are extracted: run.json present with exit status 0. A run that was killed
(no run.json), interrupted (130, 143) or failed (1) is refused unless `allow_incomplete`, and
its shard then says so (`complete: false`, `run_exit_status`), as does the dataset card.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from uavcas.flows import FlowConfig, extract_flows
from uavcas.labels import label_flows, read_attack_log
from uavcas.rundir import RunDir, RunDirError, RunInfo


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
    complete: bool = True  # the run finished with exit status 0
    run_exit_status: int | None = 0  # run.json's (None: the run never wrote one)


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
    allow_incomplete: bool = False,
) -> Shard:
    """Flows + labels of one run. The run id is `run_id`, else run.json's, else the dir's name.

    Raises RunDirError for a run that did not finish cleanly, unless `allow_incomplete`."""
    rd = RunDir(Path(run_dir))
    if not rd.root.is_dir():
        raise RunDirError(f"{rd.root}: not a directory")
    plan = rd.read_plan()
    if plan.scenario is None:
        raise RunDirError(f"{rd.plan_json}: config {plan.config!r} is no scenario (no axes to record)")
    info = rd.read_info()
    problem = incomplete_reason(info)
    if problem and not allow_incomplete:
        raise RunDirError(f"{rd.root}: {problem}; extract it anyway with --allow-incomplete (marked incomplete)")
    pcaps = rd.pcaps()
    if not pcaps:
        raise RunDirError(f"{rd.root}: no captures in {rd.pcap_dir}")
    cfg = FlowConfig(view=view, min_packets=min_packets)  # type: ignore[arg-type]
    ex = extract_flows(pcaps, cfg, points=[p.stem for p in pcaps], allow_truncated=allow_truncated)
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
            min_packets=cfg.effective_min_packets,
            n_packets=len(ex.packets),
            n_flows=len(df),
            class_counts=counts,
            truncations=[f"{t.path}@{t.offset}" for t in ex.packets.truncations],
            extracted_unix=time.time(),
            complete=problem is None,
            run_exit_status=info.exit_status if info else None,
        ),
    )


def incomplete_reason(info: RunInfo | None) -> str | None:
    """Why a run's data is incomplete (None: it finished with exit status 0)."""
    if info is None:
        return "the run never finished (no run.json: killed, or still running)"
    if info.exit_status != 0:
        return f"the run did not finish cleanly (exit status {info.exit_status}: {info.exit_reason})"
    return None
