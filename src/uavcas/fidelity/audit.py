"""`audit(run_dir) -> Fidelity`: follow every packet of a run and hold each hop to the plan.

Per hop crossing (a packet seen at switch i, then at the next switch j; `uavcas.flows.follow`)
the measured hop delay is compared with the FIFO model of the plan (`fifo`), fed the shaping
in force on the port at the time (`inforce`): the delay error. Per link direction and window:
delay-error quantiles, loss split by cause (`losses`: the kernel's counters where the run logged
them, else how full the model's queue was) with random loss against the planned loss,
throughput in saturated bins (the model's queue never empty for the whole bin) against the
planned rate, each frame spread over its serialisation time (`throughput`); crossings that
brought a packet back to a switch it had crossed (loops, `flows.copies`). Per flow: how much
the emulator moved inter-packet gaps end to end. A window that an attack re-shaped in its
middle (a jammer's overrides: `inforce`) is audited per segment, each against the parameters in
force in it (the jammed plan during the jammer's span, the unjammed outside it), with that
segment's kernel counters. The pooled
figures, the packets that looped and the schedule (window change time, lateness from run.json)
are checked against `Tolerances`, one set for every swarm size; any failed check fails the run.

Losses during a change of forwarding (a window change or an attack re-routing: from
`TRANSITION_S` before the change began to `TRANSITION_S` after it ended) and losses on a link
that left the plan before the packet could have arrived are counted apart as transition losses
(`lost` includes them, random loss does not): the plan says nothing about packets in flight
while the topology changes, and the window-change check bounds how long that lasts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from uavcas.flows.follow import Followed, Timeline, follow, node_of_point, run_timeline
from uavcas.flows.packets import PacketTable, read_packets
from uavcas.rundir import RunDir, RunInfo
from uavcas.twin.model import Plan

from . import fifo, losses, throughput
from .inforce import PortCapacity, PortShaping, planned_settings, port_shaping, shape_spans
from .loops import rerouted_in_flight
from .model import Check, Counters, Fidelity, GapDistortion, LinkWindow, Tolerances

TRANSITION_S = 0.05  # margin around a forwarding change (held packets, queues draining)
# a frame the model sends within this long after another enters is timing noise, not backlog
# (`queue_over_limit`: a 54-byte frame at 0.5 Mbit/s takes 0.8 ms)
OVER_LIMIT_SLACK_S = 0.001
SEGMENTS = 64  # segments a window can have (keys: (window * SEGMENTS + segment) * n + i) * n + j)


@dataclass
class _Planned:
    """Planned link parameters by (window, i, j) as dense arrays (NaN: no such link)."""

    delay_ms: np.ndarray
    rate_mbps: np.ndarray
    loss: np.ndarray

    @classmethod
    def of(cls, plan: Plan) -> "_Planned":
        n, w = len(plan.nodes), len(plan.windows)
        idx = {x.name: x.index for x in plan.nodes}
        arrs = [np.full((w, n, n), np.nan) for _ in range(3)]
        for win in plan.windows:
            for lk in win.links:
                i, j = idx[lk.a], idx[lk.b]
                for a, v in zip(arrs, (lk.delay_ms, lk.rate_mbps, lk.loss)):
                    a[win.index, i, j] = a[win.index, j, i] = v
        return cls(*arrs)


@dataclass(frozen=True)
class _Port:
    """The FIFO model of one link direction over the whole run (frames in service order)."""

    shaping: PortShaping
    entered_sorted: np.ndarray  # when each frame entered the queue, ascending
    ready: np.ndarray
    start: np.ndarray  # non-decreasing (FIFO)
    rows: np.ndarray  # crossing indices

    def backlog(self, t: np.ndarray) -> np.ndarray:
        """Frames in the queue at each time t (entered at or before t, not started)."""
        return (np.searchsorted(self.entered_sorted, t, side="right")
                - np.searchsorted(self.start, t, side="right")).astype(np.int64)

    def held_before(self, entered: np.ndarray, slack_s: float = 0.0) -> np.ndarray:
        """Frames the queue held just before a frame entered at each time (those entered earlier),
        not counting those it sends within `slack_s` after."""
        return (np.searchsorted(self.entered_sorted, entered, side="left")
                - np.searchsorted(self.start, entered + slack_s, side="right")).astype(np.int64)


def _q(x: np.ndarray, p: float) -> float | None:
    return round(float(np.percentile(x, p)), 4) if x.shape[0] else None


def delay_errors(err_ms: np.ndarray) -> dict:
    return {"n": int(err_ms.shape[0]), "delay_error_p1_ms": _q(err_ms, 1), "delay_error_p50_ms": _q(err_ms, 50),
            "delay_error_p90_ms": _q(err_ms, 90), "delay_error_p99_ms": _q(err_ms, 99),
            "delay_error_p999_ms": _q(err_ms, 99.9),
            "delay_error_max_ms": round(float(err_ms.max()), 4) if err_ms.shape[0] else None,
            "late_over_1ms": round(float((err_ms > 1.0).mean()), 6) if err_ms.shape[0] else None}


def audit(run_dir: str | Path, tolerances: Tolerances | None = None, table: PacketTable | None = None) -> Fidelity:
    """Audit one run directory (see the module docstring); nothing is written.

    `tolerances`: default `Tolerances()`, the same for every swarm size.
    """
    rd = RunDir(Path(run_dir))
    plan, info = rd.read_plan(), rd.read_info()
    if tolerances is None:
        tolerances = Tolerances()
    timeline = run_timeline(rd, plan)
    shaping = port_shaping(plan, timeline, shape_spans(rd.read_attacks()))
    if table is None:
        table = read_packets(rd.pcaps(), allow_truncated=True)
    # identical copies are paired knowing the rates each port held (a jammer's included)
    fol = follow(table, timeline, tolerances.max_hop_s, PortCapacity(shaping))
    return _Audit(plan, info, rd, table, fol, timeline, shaping, tolerances).report()


class _Audit:
    def __init__(self, plan: Plan, info: RunInfo | None, rd: RunDir, table: PacketTable, fol: Followed,
                 timeline: Timeline, shaping: dict[tuple[int, int], PortShaping], tol: Tolerances) -> None:
        self.plan, self.info, self.rd, self.table = plan, info, rd, table
        self.fol, self.tl, self.tol = fol, timeline, tol
        self.planned = _Planned.of(plan)
        index = {x.name: x.index for x in plan.nodes}
        self.point_node = np.array([index.get(node_of_point(p) or "", -1) for p in fol.points] or [-1], dtype=np.int64)
        self.names = [x.name for x in plan.nodes]
        self.n = len(self.names)
        self.t0 = info.t0_unix if info is not None and info.t0_unix is not None else float(timeline.t_unix[0])
        self.shaping = shaping
        self.setting = planned_settings(self.shaping)  # (window, segment, i, j) -> (delay, rate, loss)
        self.netem = info is not None and info.shaper_backend == "netem"
        self.shaping_records = rd.read_shaping()  # shaping.jsonl, read once: bursts and counters
        self.bursts = {(r["window"], r.get("segment", 0), r["src"], r["dst"]): r["applied_burst_b"]
                       for r in self.shaping_records if r.get("applied_burst_b") is not None}
        self._crossings()
        self._losses()
        self._revisits()

    def _revisits(self) -> None:
        """Packets back at a switch they had crossed: loops (faults) or re-routed in flight (`loops`)."""
        pids = np.unique(self.c.pid[self.c.revisit])
        fine = rerouted_in_flight(self.fol, self.point_node, self.tl, pids)
        self.looped_pids, self.rerouted_pids = pids[~fine], pids[fine]
        self.c_loop = self.c.revisit & np.isin(self.c.pid, self.looped_pids)  # per crossing

    def _has(self, w: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        W = self.planned.delay_ms.shape[0]
        ok = (i >= 0) & (j >= 0) & (w >= 0) & (w < W)
        return ok & ~np.isnan(self.planned.delay_ms[np.clip(w, 0, W - 1), np.maximum(i, 0), np.maximum(j, 0)])

    def _param(self, arr: np.ndarray, w: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        ok = w >= 0
        return np.where(ok, arr[np.maximum(w, 0), np.maximum(i, 0), np.maximum(j, 0)], np.nan)

    def _by_port(self, direction: np.ndarray, t: np.ndarray):
        """(direction key, its `PortShaping`, rows, setting in force at each row's `t`) per shaped
        link direction, rows of times before the port was shaped left out."""
        by_dir = np.argsort(direction, kind="stable")
        for g in np.split(by_dir, np.flatnonzero(np.diff(direction[by_dir])) + 1) if by_dir.shape[0] else []:
            key = int(direction[g[0]])
            ps = self.shaping.get(divmod(key, self.n)) if key >= 0 else None
            if ps is not None:
                k = ps.at(t[g])
                yield key, ps, g[k >= 0], k[k >= 0]

    # per crossing ----------------------------------------------------------------------------
    def _crossings(self) -> None:
        """Every crossing of a port with known shaping goes through that port's FIFO (it loads the
        queue whichever window it is reported in), with the shaping in force (`inforce`)."""
        c = self.fol.crossings()
        i, j = self.point_node[c.from_point], self.point_node[c.to_point]
        length = self.table["frame_len"][c.row_from].astype(np.float64)
        direction = np.where((i >= 0) & (j >= 0), i * self.n + j, -1)
        w = np.full(len(c), -1, dtype=np.int64)
        sg = np.zeros(len(c), dtype=np.int64)
        start = np.full(len(c), np.nan)
        held = np.zeros(len(c), dtype=np.int64)
        limit = np.zeros(len(c), dtype=np.int64)
        self.ports: dict[int, _Port] = {}
        for key, ps, g, k in self._by_port(direction, c.t_from):
            ready = c.t_from[g] + ps.delay_ms[k] / 1000.0
            o = np.lexsort((c.t_from[g], ready))
            g, k, ready = g[o], k[o], ready[o]
            w[g], sg[g] = ps.window[k], ps.segment[k]
            start[g] = fifo.serve(ready, length[g], ps.t_s, ps.rate_mbps, self._burst(key, ps), ps.until_s,
                                  c.t_to[g])
            entered = c.t_from[g] if self.netem else ready
            port = _Port(ps, np.sort(entered), ready, start[g], g)
            self.ports[key] = port
            held[g] = np.maximum(port.held_before(entered, OVER_LIMIT_SLACK_S), 0)
            limit[g] = ps.queue_limit_pkts(ps.at(entered), self.netem)
        self.c, self.ci, self.cj, self.cw, self.cs = c, i, j, w, sg
        self.c_len, self.c_start = length, start
        self.err_ms = (c.t_to - start) * 1000.0
        # the real queue took these frames, so it was not full: a model holding its limit is wrong
        self.c_over = ~np.isnan(start) & (held >= limit)

    def _burst(self, key: int, ps: PortShaping) -> np.ndarray:
        """The HTB bucket depth (bytes) of each of a port's settings, as the run logged the kernel
        held it (shaping.jsonl `applied_burst_b`); where it did not (runs made before it was
        logged), tc's default on this kernel, `Tolerances.burst_bytes`."""
        src, dst = self.names[key // self.n], self.names[key % self.n]
        return np.array([self.bursts.get((int(w), int(sg), src, dst), self.tol.burst_bytes)
                         for w, sg in zip(ps.window, ps.segment)], dtype=np.float64)

    # losses ----------------------------------------------------------------------------------
    def _losses(self) -> None:
        lo = self.fol.losses
        routed = lo.to_point >= 0
        i = self.point_node[lo.from_point]
        j = np.where(routed, self.point_node[np.maximum(lo.to_point, 0)], -1)
        w = np.full(len(lo), -1, dtype=np.int64)
        sg = np.zeros(len(lo), dtype=np.int64)
        t_in = lo.t_s.copy()  # when it would have entered the queue
        backlog = np.zeros(len(lo), dtype=np.int64)
        limit = np.ones(len(lo), dtype=np.int64)
        direction = np.where((i >= 0) & (j >= 0), i * self.n + j, -1)
        for key, ps, g, k in self._by_port(direction, lo.t_s):
            w[g], sg[g] = ps.window[k], ps.segment[k]
            if not self.netem:
                t_in[g] += ps.delay_ms[k] / 1000.0
            port = self.ports.get(key)
            if port is not None:
                backlog[g] = port.backlog(t_in[g])
            limit[g] = ps.queue_limit_pkts(ps.at(t_in[g]), self.netem)
        d = np.nan_to_num(self._param(self.planned.delay_ms, w, i, j))
        t_ready = lo.t_s + d / 1000.0
        # the link left the plan before the packet could have arrived, or forwarding was changing
        down = (w >= 0) & ~self._has(self.tl.window_at(t_ready + TRANSITION_S).astype(np.int64), i, j)
        for b, e in zip(self.tl.t_begin_unix[1:], self.tl.t_unix[1:]):
            down |= (lo.t_s >= b - TRANSITION_S) & (lo.t_s <= e + TRANSITION_S)
        self.li, self.lj, self.lw, self.ls, self.l_transition = i, j, w, sg, down
        self.l_backlog, self.l_limit = backlog, limit
        self.l_label = np.full(len(lo), losses.UNEXPLAINED, dtype=np.int8)  # set per link-window (_links)

    # aggregates --------------------------------------------------------------------------------
    def _saturation(self, port: _Port) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Saturated bins of one direction (`throughput`): (bin start times, measured/planned
        rate, setting as window * SEGMENTS + segment)."""
        rows = port.rows
        t_bin, ratio, s = throughput.saturated_ratios(port.ready, port.start, self.c.t_to[rows], self.c_len[rows],
                                                      port.shaping, self.t0, self.tol.saturated_bin_s)
        return t_bin, ratio, port.shaping.window[s] * SEGMENTS + port.shaping.segment[s]

    def _gaps(self) -> GapDistortion:
        c, ok = self.c, ~np.isnan(self.err_ms)
        npk = self.fol.n_packets
        if len(c) == 0:
            return GapDistortion(gaps=0, gap_p50_ms=None, shift_p50_ms=None, shift_p90_ms=None,
                                 shift_over_half_gap=None)
        e2e = np.bincount(c.pid, weights=np.where(ok, self.err_ms, 0.0), minlength=npk)
        bad = np.bincount(c.pid, weights=(~ok).astype(float), minlength=npk) > 0
        ncross = np.bincount(c.pid, minlength=npk)
        first = self.fol.order[self.fol.offsets[:-1]]
        last = self.fol.order[self.fol.offsets[1:] - 1]
        use = (ncross > 0) & ~bad
        t = self.table
        keys = [t[k][first] for k in ("src_hi", "src_lo", "dst_hi", "dst_lo", "proto", "sport", "dport")]
        keys.append(t["point"][last])
        t_first, t_last = t["ts_s"][first], t["ts_s"][last]
        pids = np.flatnonzero(use)
        o = pids[np.lexsort((t_first[pids], *[k[pids] for k in reversed(keys)]))]
        same = np.ones(max(o.shape[0] - 1, 0), dtype=bool)
        for k in keys:
            same &= k[o][1:] == k[o][:-1]
        p, q = o[:-1][same], o[1:][same]
        shift = e2e[q] - e2e[p]
        gap_model = (t_last[q] - t_last[p]) * 1000.0 - shift
        a = np.abs(shift)
        return GapDistortion(gaps=int(p.shape[0]), gap_p50_ms=_q(gap_model, 50), shift_p50_ms=_q(a, 50),
                             shift_p90_ms=_q(a, 90),
                             shift_over_half_gap=round(float((a > 0.5 * np.abs(gap_model)).mean()), 6) if a.shape[0]
                             else None)

    def _links(self, sat: dict[tuple[int, int, int], np.ndarray]) -> list[LinkWindow]:
        n = self.n
        counters = self._counters()
        index = {x: k for k, x in enumerate(self.names)}
        ck = np.where(self.cw >= 0, ((self.cw * SEGMENTS + self.cs) * n + self.ci) * n + self.cj, -1)
        lk = np.where(self.lw >= 0, ((self.lw * SEGMENTS + self.ls) * n + self.li) * n + self.lj, -1)
        # link-windows the kernel saw traffic on count for the loss test even if no packet was followed
        kk = [((w * SEGMENTS + sg) * n + index[a]) * n + index[b] for (w, sg, a, b), c in counters.items()
              if a in index and b in index and (w, sg, index[a], index[b]) in self.setting
              and losses.counted(c) and c.sent_packets + c.queue_drops + c.loss_drops > 0]
        keys = np.union1d(np.union1d(np.unique(ck[ck >= 0]), np.unique(lk[lk >= 0])), np.array(kk, dtype=np.int64))
        order = np.argsort(ck, kind="stable")
        bounds = np.searchsorted(ck[order], keys), np.searchsorted(ck[order], keys, side="right")
        l_order = np.lexsort((self.fol.losses.t_s, lk))
        l_bounds = np.searchsorted(lk[l_order], keys), np.searchsorted(lk[l_order], keys, side="right")
        out = []
        for key, a, b, la, lb in zip(keys.tolist(), *bounds, *l_bounds):
            rows, mine = order[a:b], l_order[la:lb]
            ws, rest = divmod(key, n * n)
            i, j = divmod(rest, n)
            w, sg = divmod(ws, SEGMENTS)
            cnt = counters.get((w, sg, self.names[i], self.names[j]))
            delay, rate, p = self.setting.get((w, sg, i, j), (float(self.planned.delay_ms[w, i, j]),
                                                              float(self.planned.rate_mbps[w, i, j]),
                                                              float(self.planned.loss[w, i, j])))
            labels, stage = losses.classify(self.l_backlog[mine], self.l_limit[mine], self.l_transition[mine],
                                            rows.shape[0], cnt, p)
            self.l_label[mine] = labels
            self.stages.append(stage)
            sigma = _sigma(stage.dropped, stage.offered, p)
            ratios = sat.get((ws, i, j), np.zeros(0))
            de = delay_errors(self.err_ms[rows])
            ok = _delay_ok(de, self.tol) and abs(sigma or 0.0) <= self.tol.loss_sigma
            meas = (self.c.t_to[rows] - self.c.t_from[rows]) * 1000.0
            model = (self.c_start[rows] - self.c.t_from[rows]) * 1000.0
            count = np.bincount(labels, minlength=4)
            out.append(LinkWindow(
                verdict="pass" if ok else "fail", src=self.names[i], dst=self.names[j], window=w, segment=sg, **de,
                planned_delay_ms=delay, planned_rate_mbps=rate, planned_loss=p,
                measured_delay_p50_ms=_q(meas, 50), model_delay_p50_ms=_q(model, 50),
                queue_over_limit=int(self.c_over[rows].sum()), loops=int(self.c_loop[rows].sum()),
                rerouted=int((self.c.revisit[rows] & ~self.c_loop[rows]).sum()),
                lost=int(mine.shape[0]),
                lost_tail=int(count[losses.TAIL]), lost_random=int(count[losses.RANDOM]),
                lost_transition=int(count[losses.TRANSITION]), lost_unexplained=int(count[losses.UNEXPLAINED]),
                loss_source=stage.source, loss_offered=stage.offered, loss_drops=stage.dropped,
                loss_random=round(stage.dropped / stage.offered, 6) if stage.offered else None,
                loss_sigma=sigma, saturated_bins=int(ratios.shape[0]), throughput_ratio_p50=_q(ratios, 50),
                counters=cnt))
        return out

    def _counters(self) -> dict[tuple[int, str, str], Counters]:
        out = {}
        for r in self.shaping_records:
            fields = {k: r.get(k) for k in Counters.model_fields}
            if any(v is not None for v in fields.values()):
                out[(r["window"], r.get("segment", 0), r["src"], r["dst"])] = Counters(**fields)
        return out

    def report(self) -> Fidelity:
        tol = self.tol
        sat: dict[tuple[int, int, int], np.ndarray] = {}
        all_ratios = []
        for key, port in self.ports.items():
            _, ratio, w = self._saturation(port)
            i, j = divmod(key, self.n)
            for wk in np.unique(w).tolist():
                sat[(wk, i, j)] = ratio[w == wk]
            all_ratios.append(ratio)
        ratios = np.concatenate(all_ratios) if all_ratios else np.zeros(0)
        self.stages: list[losses.LossStage] = []
        links = self._links(sat)
        err = self.err_ms[~np.isnan(self.err_ms)]
        pooled = delay_errors(err)
        rnd_obs = sum(st.dropped for st in self.stages)
        exp = sum(st.expected for st in self.stages)
        sigma = _sigma_pooled(rnd_obs, exp, sum(st.variance for st in self.stages))
        looped = int(self.looped_pids.shape[0])
        change = [a.timings_s.get("total_s", 0.0) * 1000 for a in self.info.window_applies] if self.info else []
        late = [e.late_ms for e in self.info.schedule] if self.info else []
        checks = [
            Check(name="delay_error_p50_ms", value=pooled["delay_error_p50_ms"], limit=tol.delay_error_p50_ms,
                  ok=_le(abs(pooled["delay_error_p50_ms"] or 0.0), tol.delay_error_p50_ms)),
            Check(name="delay_error_p90_ms", value=pooled["delay_error_p90_ms"], limit=tol.delay_error_p90_ms,
                  ok=_le(pooled["delay_error_p90_ms"], tol.delay_error_p90_ms)),
            Check(name="delay_error_p99_ms", value=pooled["delay_error_p99_ms"], limit=tol.delay_error_p99_ms,
                  ok=_le(pooled["delay_error_p99_ms"], tol.delay_error_p99_ms)),
            Check(name="delay_early_p1_ms", value=pooled["delay_error_p1_ms"], limit=-tol.delay_early_p1_ms,
                  ok=pooled["delay_error_p1_ms"] is None or pooled["delay_error_p1_ms"] >= -tol.delay_early_p1_ms),
            Check(name="loss_sigma", value=sigma, limit=tol.loss_sigma,
                  ok=sigma is None or abs(sigma) <= tol.loss_sigma),
            Check(name="throughput_rel", value=_q(ratios, 50), limit=tol.throughput_rel,
                  ok=ratios.shape[0] == 0 or abs(float(np.median(ratios)) - 1) <= tol.throughput_rel),
            Check(name="loops", value=looped, limit=tol.loops, ok=looped <= tol.loops),
            Check(name="window_change_ms", value=round(max(change), 3) if change else None, limit=tol.window_change_ms,
                  ok=not change or max(change) <= tol.window_change_ms),
            Check(name="lateness_ms", value=round(max(late), 3) if late else None, limit=tol.lateness_ms,
                  ok=not late or max(late) <= tol.lateness_ms),
        ]
        failed = [ch.name for ch in checks if not ch.ok]
        count = np.bincount(self.l_label, minlength=4)
        return Fidelity(
            verdict="fail" if failed else "pass", failed=failed, **pooled, packets=self.fol.n_packets,
            crossings_unmodelled=int(np.isnan(self.err_ms).sum()), queue_over_limit=int(self.c_over.sum()),
            loops=looped, rerouted=int(self.rerouted_pids.shape[0]), lost=len(self.fol.losses),
            lost_tail=int(count[losses.TAIL]),
            lost_random=int(count[losses.RANDOM]), lost_transition=int(count[losses.TRANSITION]),
            lost_unexplained=int(count[losses.UNEXPLAINED]),
            loss_links_counted=sum(st.source == "counters" for st in self.stages),
            loss_offered=sum(st.offered for st in self.stages), loss_random_observed=rnd_obs,
            loss_random_expected=round(exp, 3), loss_sigma=sigma, throughput_ratio_p50=_q(ratios, 50),
            saturated_bins=int(ratios.shape[0]), gaps=self._gaps(),
            window_change_max_ms=round(max(change), 3) if change else None,
            lateness_max_ms=round(max(late), 3) if late else None, checks=checks, tolerances=tol, links=links)


def _delay_ok(de: dict, tol: Tolerances) -> bool:
    return (_le(abs(de["delay_error_p50_ms"] or 0.0), tol.delay_error_p50_ms)
            and _le(de["delay_error_p90_ms"], tol.delay_error_p90_ms)
            and _le(de["delay_error_p99_ms"], tol.delay_error_p99_ms)
            and (de["delay_error_p1_ms"] is None or de["delay_error_p1_ms"] >= -tol.delay_early_p1_ms))


def _le(x: float | None, limit: float) -> bool:
    return x is None or x <= limit


def _sigma(observed: int, offered: int, p: float) -> float | None:
    if offered == 0:
        return None
    return _sigma_pooled(observed, offered * p, offered * p * (1 - p))


def _sigma_pooled(observed: float, expected: float, var: float) -> float:
    """(observed - expected) in binomial standard deviations, the variance floored at one loss:
    a lossless plan tolerates a few unexplained losses (as many as `loss_sigma`), not none."""
    return round((observed - expected) / math.sqrt(max(var, 1.0)), 3)
