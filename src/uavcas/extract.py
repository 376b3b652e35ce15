"""The extraction stage: `extract(run_dir) -> Shard`, one run's labelled flows with their axes.

Captures -> every packet followed across the switches (`uavcas.flows.follow`) -> flows
(`uavcas.flows`; each transmission counted once, even one that missed its flow's vantage point)
-> one effect per packet and labels from them (`uavcas.labels`) -> identity
and axis columns from the plan's typed scenario (nothing here parses the config string). Writing
the shard and the dataset card is `uavcas.dataset.store`'s job.

Only complete runs are extracted: run.json present with exit status 0. A run that was killed
(no run.json), interrupted (130, 143) or failed (1) is refused unless `allow_incomplete`, and
its shard then says so (`complete: false`, `run_exit_status`), as does the dataset card.

The context columns (`ctx_*`, `uavcas.flows.context`) are computed from the captures and flows
alone, before anything reads the plan's attacks or the attack log. (The flows' vantage rule asks
the follower which observations are one transmission; the follower chains them along the
forwarding the run held, a wormhole's tables included, and reads no attack log or truth. What it
changes is which observation of a packet a flow keeps, never a feature's formula.)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from uavcas.flows import DEFAULT_STANDARD, FlowConfig, Flows, PacketTable, flows_of, read_packets
from uavcas.flows.context import CONTEXT_WINDOW_S, context_frames
from uavcas.flows.follow import Followed, follow_run
from uavcas.labels import read_attack_log
from uavcas.labels.effects import PacketTruth, TruthContext, packet_truth
from uavcas.rundir import RunDir, RunDirError, RunInfo
from uavcas.views import DEFAULT_VIEW, ViewInput
from uavcas.views import view as view_spec
from uavcas.vocabulary import EFFECTS

if TYPE_CHECKING:
    from uavcas.twin.model import Plan


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
    min_attack_fraction: float
    impure_dropped: int  # flows left out: attack packets, but attack_fraction < min_attack_fraction
    effect_counts: dict[str, int]  # captured packet observations per effect (all capture points)
    label_rule: str
    truncations: list[str]
    extracted_unix: float
    profile: str | None = None  # twin profile the run's plan was made with, and its SHA-256
    profile_sha256: str | None = None
    fidelity: str | None = None  # the run's fidelity verdict (run.json), None: never audited
    # the checks it failed (verdict fail), or why the audit could not be made (verdict error)
    fidelity_failed: list[str] = field(default_factory=list)
    complete: bool = True  # the run finished with exit status 0
    run_exit_status: int | None = 0  # run.json's (None: the run never wrote one)
    context_window_s: float | None = None  # window of the ctx_* columns, None: not computed
    mavlink_signing: bool | None = None  # run.json's: MAVLink 2 signing on (None: no run.json)


@dataclass(frozen=True)
class Shard:
    frame: pd.DataFrame  # one row per row of the view (`uavcas.views`: its metadata, features and context columns)
    info: ShardInfo  # `features` and `view` say what the frame's columns are (the shard writer reads them)


def _fidelity_failed(info) -> list[str]:
    fid = info.fidelity if info is not None else None
    if fid is None:
        return []
    return list(fid.failed) if fid.verdict != "error" else [f"audit error: {fid.error or 'unknown'}"]


def _check_run_id(run_dir: Path, rid: str) -> str:
    if not rid or "/" in rid or rid.startswith("."):
        raise RunDirError(f"{run_dir}: unusable run id {rid!r}")
    return rid


@dataclass(frozen=True)
class Extracted:
    """A shard and what it was made from: the packet table (every capture point), its flows
    (`frame.flow_id` numbers them), the followed transmissions and each packet's truth."""

    shard: Shard
    packets: PacketTable
    flows: Flows
    followed: Followed
    truth: PacketTruth


def extract(run_dir: Path | str, **options: Any) -> Shard:
    """Flows + labels of one run (options: those of `extract_detailed`)."""
    return extract_detailed(run_dir, **options).shard


def extract_detailed(
    run_dir: Path | str,
    view: str = DEFAULT_VIEW,
    labels: str = "ours",
    min_packets: int | None = None,
    allow_truncated: bool = False,
    run_id: str | None = None,
    min_attack_fraction: float = 0.0,
    features: str = DEFAULT_STANDARD,
    allow_incomplete: bool = False,
    context: bool = True,
    termination: str | None = None,
) -> Extracted:
    """Flows + labels of one run, with the packet-level results (for audits and tests). The run id
    is `run_id`, else run.json's, else the directory's name. `context`: add the `ctx_*` columns.
    `termination`: the flow termination policy (`uavcas.flows.termination`; None: the view's default).

    `view`: what the rows are (`uavcas.views`: a flow of a flow key, or the window-host view's
    episodes, built from the 5-tuple flows): the view's flows are made here, its rows and labels by the view.

    Raises RunDirError for a run that did not finish cleanly, unless `allow_incomplete`."""
    spec = view_spec(view)
    spec.check_options(labels, min_attack_fraction)
    rd = RunDir(Path(run_dir))
    plan, pcaps, t0 = run_inputs(rd)
    if plan.scenario is None:
        raise RunDirError(f"{rd.plan_json}: config {plan.config!r} is no scenario (no axes to record)")
    info = rd.read_info()
    problem = incomplete_reason(info)
    if problem and not allow_incomplete:
        raise RunDirError(f"{rd.root}: {problem}; extract it anyway with --allow-incomplete (marked incomplete)")
    cfg = FlowConfig(view=spec.flow_key, termination=termination,  # type: ignore[arg-type]
                     min_packets=min_packets, window_t0_unix=t0, window_s=plan.window_s)
    packets = read_packets(pcaps, points=[p.stem for p in pcaps], allow_truncated=allow_truncated)
    _, followed = follow_run(rd.root, table=packets)  # the captures and the forwarding the run held
    ex = flows_of(packets, cfg, transmissions=followed.pid, standard=features)
    # from the captures and flows only: computed before the attack log is even read
    ctx, routes = context_frames(ex.packets, ex.flows) if context else (None, None)
    log, followed, truth = run_truth(rd, ex.packets, plan, t0, followed)
    made = spec.rows(ViewInput(ex.packets, ex.flows, ex.frame, ctx, routes, log, truth, plan, t0, features, labels,
                               min_attack_fraction))
    df, impure, rule = made.frame, made.impure_dropped, made.label_rule
    rid = _check_run_id(rd.root, str(run_id or (info.run_id if info else None) or rd.root.resolve().name))
    df["run_id"], df["config"], df["seed"], df["view"] = rid, plan.config, plan.seed, view
    for k, v in plan.scenario.axes().items():
        df[k] = v
    counts = {str(k): int(v) for k, v in df["label"].value_counts().items()}
    effects = np.bincount(truth.effect.astype(np.int64), minlength=len(EFFECTS))
    shard = Shard(
        frame=df,
        info=ShardInfo(
            run_id=rid,
            config=plan.config,
            seed=plan.seed,
            view=view,
            labels=labels,
            features=features,
            flow_rules={**cfg.describe(), "missed_transmissions": "kept once, at their last observation"},
            min_packets=cfg.effective_min_packets,
            n_packets=len(ex.packets),
            n_flows=len(df),
            class_counts=counts,
            min_attack_fraction=float(min_attack_fraction),
            impure_dropped=impure,
            effect_counts={e: int(c) for e, c in zip(EFFECTS, effects)},
            label_rule=rule,
            truncations=[f"{t.path}@{t.offset}" for t in ex.packets.truncations],
            extracted_unix=time.time(),
            profile=plan.profile,
            profile_sha256=plan.profile_sha256,
            fidelity=info.fidelity.verdict if info is not None and info.fidelity is not None else None,
            fidelity_failed=_fidelity_failed(info),
            complete=problem is None,
            run_exit_status=info.exit_status if info else None,
            context_window_s=CONTEXT_WINDOW_S if context else None,
            mavlink_signing=info.mavlink_signing if info is not None else None,
        ),
    )
    return Extracted(shard, ex.packets, ex.flows, followed, truth)


def run_inputs(rd: RunDir) -> tuple["Plan", list[Path], float]:
    """A run's plan, its captures and its t0, or a RunDirError naming what is missing."""
    if not rd.root.is_dir():
        raise RunDirError(f"{rd.root}: not a directory")
    plan = rd.read_plan()
    pcaps = rd.pcaps()
    if not pcaps:
        raise RunDirError(f"{rd.root}: no captures in {rd.pcap_dir}")
    t0 = rd.read_t0()
    if t0 is None:
        raise RunDirError(f"{rd.root}: the run never reached its plan's t = 0 (no t0_unix in run.json or "
                          f"{rd.owner_path.name}): its packets cannot be placed in the plan")
    return plan, pcaps, t0


def run_truth(rd: RunDir, packets: PacketTable, plan: "Plan", t0: float, followed: Followed | None = None):
    """The attack log, the followed transmissions (unless given) and every packet's truth
    (`labels.effects`)."""
    log = read_attack_log(rd.attacks_jsonl, plan, t0)
    if followed is None:
        _, followed = follow_run(rd.root, table=packets)
    return log, followed, packet_truth(TruthContext(packets, log, followed, plan, t0))


def incomplete_reason(info: RunInfo | None) -> str | None:
    """Why a run's data is incomplete (None: it finished with exit status 0)."""
    if info is None:
        return "the run never finished (no run.json: killed, or still running)"
    if info.exit_status != 0:
        return f"the run did not finish cleanly (exit status {info.exit_status}: {info.exit_reason})"
    return None
