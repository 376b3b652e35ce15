"""fidelity.json, typed: what a run's audit measured against its plan, and its verdict.

Delay errors are *measured minus model* per hop crossing, in milliseconds (positive: the
emulator was late); the model is `uavcas.fidelity.fifo`. Quantiles are of the signed error.
Lost packets are split by `uavcas.fidelity.losses`. Schema 2 added the loss stage's own figures
(`loss_source`, `loss_offered`, `loss_drops`), `lost_random`, `lost_unexplained` and
`queue_over_limit`; schema 3 added `loops` (run and link-window) and the `loops` tolerance and
check; schema 4 `rerouted` (packets back at a switch after a window change, each hop by the
table in force: no loop, `fidelity.loops`), which schema 3 counted as loops. They default to
None (the tolerance to 0) when an older file is read.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from uavcas.rundir import FidelitySummary

SCHEMA_VERSION = 4
Verdict = Literal["pass", "fail"]


class _Strict(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class Tolerances(_Strict):
    """Limits a run must keep to pass: issue #14's targets, one set for every swarm size (a larger
    swarm loads the emulator more, which is what the audit is there to catch, not to excuse)."""

    delay_error_p50_ms: float = Field(0.1, description="|median| of the per-hop delay error")
    delay_error_p90_ms: float = Field(0.2, description="90th percentile of the per-hop delay error")
    delay_error_p99_ms: float = Field(0.5, description="99th percentile of the per-hop delay error")
    delay_early_p1_ms: float = Field(0.2, description="1st percentile may be at most this early")
    loss_sigma: float = Field(4.0, description="random loss: |observed - planned| in binomial standard deviations")
    throughput_rel: float = Field(0.05, description="|measured/planned - 1| on saturated links (median of bins)")
    # issue 28's limit at every swarm size (stop 26: 60-70 ms at 100 UAVs, at most 70 ms over the
    # 100 runs of the medium campaign)
    window_change_ms: float = Field(100.0, description="longest window change (apply) of the run")
    lateness_ms: float = Field(100.0, description="latest scheduled event of the run")
    loops: float = Field(0.0, description="packets that looped (`fidelity.loops`: not re-routed in flight)")
    max_hop_s: float = Field(1.0, description="longest plausible hop (the packet follower)")
    saturated_bin_s: float = Field(0.2, description="bin width for throughput on saturated links")
    burst_bytes: float = Field(1600.0, description="token-bucket depth of the rate stage (HTB burst) of runs that "
                               "did not log it (shaping.jsonl applied_burst_b): tc's default")


class DelayErrors(_Strict):
    n: int  # hop crossings modelled
    delay_error_p1_ms: float | None
    delay_error_p50_ms: float | None
    delay_error_p90_ms: float | None
    delay_error_p99_ms: float | None
    delay_error_p999_ms: float | None
    delay_error_max_ms: float | None
    late_over_1ms: float | None  # fraction of crossings more than 1 ms late


class Counters(_Strict):
    """Kernel counters of one port over one window (deltas): read at each window's end."""

    sent_packets: int | None = None  # left the rate stage
    queue_drops: int | None = None  # queue tail (pfifo) drops
    loss_drops: int | None = None  # random-loss rule drops (nft)
    link_drops: int | None = None  # dropped by the port on transmit (queue not attached yet, peer down)
    paced_packets: int | None = None  # admitted and charged by the delay stage's pacer (fallback backend)


class LinkWindow(DelayErrors):
    """One link direction (src's switch -> dst's switch) in one window, or in one segment of it
    when an attack re-shaped the link mid-window (`inforce`: a jammer's span), against the
    parameters planned for that segment.

    `verdict`: the run's delay and loss checks on this link alone. Informative only, it does not
    enter the run's verdict (quantiles of a few hundred packets are noisy).
    """

    verdict: Verdict
    src: str
    dst: str
    window: int
    segment: int = 0  # 0: as the window was applied; k: after its k-th mid-window reshape
    planned_delay_ms: float
    planned_rate_mbps: float
    planned_loss: float
    measured_delay_p50_ms: float | None  # hop delay as measured (capture to capture)
    model_delay_p50_ms: float | None  # what the model gives the same packets
    # crossings that entered a model queue already at its limit: the real queue took them, so
    # it was not full, and the model carried a backlog the port did not have (0 when it is right)
    queue_over_limit: int | None = None
    loops: int | None = None  # crossings that brought a looping packet back to a switch it had crossed (dst)
    rerouted: int | None = None  # such crossings of packets re-routed in flight (`fidelity.loops`): no fault
    lost: int  # left src, never reached dst
    lost_tail: int  # of those: dropped at the tail of the queue
    lost_random: int | None = None  # dropped by the random-loss rule
    lost_transition: int  # while forwarding changed, or the link was leaving the plan
    lost_unexplained: int | None = None  # not dropped by this port (counters): blackhole, detour, ...
    # the random-loss rule: frames it saw and dropped ("counters": the kernel's; "model": the split above)
    loss_source: Literal["counters", "model"] | None = None
    loss_offered: int | None = None
    loss_drops: int | None = None
    loss_random: float | None  # loss_drops / loss_offered
    loss_sigma: float | None  # (loss_drops - planned loss x loss_offered) / binomial sd
    saturated_bins: int
    throughput_ratio_p50: float | None  # measured / planned rate, median over saturated bins
    counters: Counters | None = None


class GapDistortion(_Strict):
    """Inter-packet gaps inside flows, end to end: how much the emulator moved them vs the model."""

    gaps: int
    gap_p50_ms: float | None  # the model's gap
    shift_p50_ms: float | None  # |measured gap - model gap|
    shift_p90_ms: float | None
    shift_over_half_gap: float | None  # fraction of gaps moved by more than half of themselves


class Check(_Strict):
    name: str
    value: float | None
    limit: float
    ok: bool


class Fidelity(DelayErrors):
    """fidelity.json: the run's pooled figures, its checks and verdict, then per link and window."""

    schema_version: int = SCHEMA_VERSION
    verdict: Verdict
    failed: list[str]  # names of the checks that failed
    packets: int  # transmissions followed
    crossings_unmodelled: int  # hop crossings of a port whose shaping was not known then
    queue_over_limit: int | None = None  # crossings that found the model's queue full (LinkWindow)
    loops: int | None = None  # packets that looped: back at a switch not explained by a table change (`fidelity.loops`)
    rerouted: int | None = None  # packets back at a switch, re-routed in flight by a window change (no fault)
    lost: int
    lost_tail: int
    lost_random: int | None = None
    lost_transition: int
    lost_unexplained: int | None = None  # lost, but not by the ports' queues or loss rules (incl. unrouted)
    loss_links_counted: int | None = None  # link-windows whose loss test used the kernel counters
    loss_offered: int | None = None  # frames the loss rules saw (summed over link-windows)
    loss_random_observed: int
    loss_random_expected: float
    loss_sigma: float
    throughput_ratio_p50: float | None
    saturated_bins: int
    gaps: GapDistortion
    window_change_max_ms: float | None
    lateness_max_ms: float | None
    checks: list[Check]
    tolerances: Tolerances
    links: list[LinkWindow]

    def to_json(self) -> str:
        return self.model_dump_json(indent=1) + "\n"


def summary(f: Fidelity) -> FidelitySummary:
    """The run.json summary of an audit."""
    return FidelitySummary(verdict=f.verdict, failed=f.failed, delay_error_p50_ms=f.delay_error_p50_ms,
                           delay_error_p90_ms=f.delay_error_p90_ms, delay_error_p99_ms=f.delay_error_p99_ms)
