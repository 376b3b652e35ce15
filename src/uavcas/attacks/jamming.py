"""Jamming: a transmitter on the swarm's carrier raises the noise floor of the links that hear it.

- token `jamming=<eirp_dbm>[,<duty_pct>[,<near|uav>]]`: the jammer's EIRP in dBm (0-60, its
  antenna gain included), its duty cycle in % (1-100, default 100: a continuous barrage jammer,
  the strongest and the simplest reading of `jamming=20`), and where it is (default `near`: a
  ground jammer beside the victim's route, the cheap commodity threat; `uav`: an attacker UAV
  carries it). Defaults are left out of the canonical token: `jamming=20`, `jamming=20,50`,
  `jamming=20,100,uav`. The band is the swarm's own carrier (the channel profile's fc);
- schedule: `near` takes no swarm node (the jammer is none: the attack has no attacker hosts),
  `uav` one attacker. Placement (`emitter`, from the plan's emitter stream): `near` puts the
  jammer, for the whole attack, at NEAR_MIN_M-NEAR_MAX_M (seeded distance and bearing) from the
  victim's position at a seeded time of the attack, at GROUND_ANTENNA_M above ground, inside
  the area: close enough that 20 dBm is ~30 dB above a -95 dBm noise floor at the victim
  (free space at 3.5 GHz, 100 m: -63 dBm), as a roadside jammer is. `uav`: the attacker UAV's
  position in each window. The plan (`twin.interference`) adds the jammer's mean power at each
  receiver to its noise floor through the links' chain (path loss with the run's model, the
  receiver's antenna gain, the wanted signal's fading; SINR -> MCS -> PER -> retries -> loss,
  MAC time, airtime share) and records, per window, the jammer (`Window.interferers`) and every
  link direction whose parameters change materially (`Window.link_overrides`, jammed values for
  the attack's span in that window; `Window.links` keep the unjammed ones). Duty cycle: a pulsed
  jammer whose period is long against one packet's retry chain (~1-10 ms) and short against a
  packet train (seconds): each packet meets it on with probability D, so the plan takes the
  mixture of the jammed and clear chains (`channel.interference`), i.e. its time average on the
  loss and MAC time, which is what a rate-shaped link of one setting can hold;
- executor: at start the current window's overrides of the attack are shaped on their ports
  through the runner's own path (`AttackExecutor.reshape`: the window's shapes with the
  overrides, `Shaper.apply`: one tc batch and one nft batch for the changed ports), and later
  windows are applied with them while the attack is active; at stop the unjammed shaping is
  restored the same way. The start is logged once the jammed shaping is in force and the stop
  just before it is undone, so [start, stop) is exactly when it held (as the blackhole's drop
  rule); each record also carries when the reshape began or ended (the audit's in-force model).
  A window with no override of the attack needs no reshape, and none is made;
- truth (effect `jamming`, label source "jamming-links"): with the plan window of the time, a
  packet lost on a link direction the plan jams (it has an override of the attack) while it
  was seen leaving the direction's first switch inside [start, stop): the jammer's loss, not
  the channel's; and a packet that crossed such a direction inside [start, stop) when the
  direction's jammed rate differs from the unjammed by >= 10 % (`twin.interference.
  MATERIAL_RATE_REL`) or its loss by >= 1 percentage point (`MATERIAL_LOSS`): the jammed MCS
  slowed or thinned the link it crossed. Every observation of such a transmission carries it;
- provoked: nothing (the default hook). A jammed link's loss leads to retransmissions that cross
  the same link and are judged by the rule itself; no packet exists only because of the jammer.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field

from uavcas.scenario_model import ScenarioError, SpecBase, choice, int_field
from uavcas.twin.interference import rate_or_loss_changed

from .base import AttackExecutor, AttackFamily, Emitter, EmitterContext, ScheduleDraw, TruthContext
from .registry import register

if TYPE_CHECKING:  # types only: the twin's and labels' package __init__s load this registry
    from uavcas.labels.attacklog import AttackWindow
    from uavcas.twin.model import Attack, LinkOverride, Window

Placement = Literal["near", "uav"]
PLACEMENTS: tuple[str, ...] = ("near", "uav")
DEFAULT_DUTY_PCT = 100
DEFAULT_PLACEMENT = "near"
NEAR_MIN_M, NEAR_MAX_M = 30.0, 120.0  # a ground jammer's distance from the victim's route
GROUND_ANTENNA_M = 2.0  # a handheld or vehicle jammer's antenna height


class JammingSpec(SpecBase):
    family: Literal["jamming"] = "jamming"
    eirp_dbm: int = Field(ge=0, le=60)
    duty_pct: int = Field(DEFAULT_DUTY_PCT, ge=1, le=100)
    placement: Placement = DEFAULT_PLACEMENT

    def token(self) -> str:
        parts = [str(self.eirp_dbm), str(self.duty_pct), self.placement]
        if self.placement == DEFAULT_PLACEMENT:
            parts = parts[:1] if self.duty_pct == DEFAULT_DUTY_PCT else parts[:2]
        return "jamming=" + ",".join(parts)


@register
class Jamming(AttackFamily):
    name = "jamming"
    spec = JammingSpec
    usage = "jamming=<eirp_dbm>[,<duty_pct>[,near|uav]]"
    truth_rule = ("a packet lost on a link direction the plan jams, seen leaving its first switch inside [start, "
                  "stop); or one that crossed such a direction inside [start, stop) when the jammed rate differs "
                  "from the unjammed by >= 10 % or the loss by >= 1 percentage point")
    provoked_rule = "nothing (retransmissions of jammed packets cross the jammed link and are judged by the rule)"
    tools = ("tc", "nft")

    def parse(self, arg: str | None, tok: str) -> JammingSpec:
        if arg is None:
            raise ScenarioError("field 'attacks': jamming needs an EIRP in dBm, e.g. jamming=20")
        parts = arg.split(",")
        if not 1 <= len(parts) <= 3:
            raise ScenarioError(f"field 'attacks': jamming takes <eirp_dbm>[,<duty_pct>[,near|uav]], got {tok!r}")
        return JammingSpec(
            eirp_dbm=int_field("attacks.jamming.eirp_dbm", parts[0], 0, 60),
            duty_pct=int_field("attacks.jamming.duty_pct", parts[1], 1, 100) if len(parts) > 1 else DEFAULT_DUTY_PCT,
            placement=choice("attacks.jamming.placement", parts[2], PLACEMENTS) if len(parts) > 2
            else DEFAULT_PLACEMENT,
        )

    def spec_from_params(self, params: dict[str, Any]) -> JammingSpec:
        return JammingSpec(**{k: params[k] for k in ("eirp_dbm", "duty_pct", "placement") if k in params})

    # schedule ----------------------------------------------------------------------------------
    def attackers(self, spec: JammingSpec, draw: ScheduleDraw) -> list[str]:  # type: ignore[override]
        return draw.take(1) if spec.placement == "uav" else []

    def emitter(self, attack: "Attack", ctx: EmitterContext) -> Emitter:
        s: JammingSpec = attack.spec  # type: ignore[assignment]
        pos = ctx.positions_m
        if s.placement == "uav":
            track = pos[:, ctx.names.index(attack.attackers[0])]
            return Emitter(track.copy(), ground=False, eirp_dbm=float(s.eirp_dbm), duty=s.duty_pct / 100.0)
        # near: a seeded point of the victim's route during the attack, a seeded offset from it
        t = float(ctx.rng.uniform(attack.start_s, attack.stop_s))
        dist, bearing = float(ctx.rng.uniform(NEAR_MIN_M, NEAR_MAX_M)), float(ctx.rng.uniform(0.0, 2 * np.pi))
        w = min(int(t // ctx.window_s), pos.shape[0] - 1)
        x0, y0, _ = pos[w, ctx.names.index(attack.victims[0])]
        x_max, y_max = ctx.area_m[0], ctx.area_m[1]
        where = np.array([min(max(x0 + dist * np.cos(bearing), 0.0), x_max),
                          min(max(y0 + dist * np.sin(bearing), 0.0), y_max), GROUND_ANTENNA_M])
        return Emitter(np.tile(where, (pos.shape[0], 1)), ground=True, eirp_dbm=float(s.eirp_dbm),
                       duty=s.duty_pct / 100.0)

    # executor ----------------------------------------------------------------------------------
    def shaping_overrides(self, ex: "AttackExecutor", attack: "Attack", window: "Window") -> list["LinkOverride"]:
        return [o for o in window.link_overrides if o.attack_id == attack.attack_id]

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        ex.active[attack.attack_id] = attack  # the window's shapes must include its overrides
        jammed = self.shaping_overrides(ex, attack, ex.window) if ex.window is not None else []
        t_begin = ex.now()
        if jammed:
            ex.reshape()
        # logged once the jammed shaping is in force
        return {"t_unix": ex.now(), "shaping_from_unix": t_begin, "jammed": [f"{o.src}>{o.dst}" for o in jammed]}

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        return self.halt(ex, attack)()

    def halt(self, ex: "AttackExecutor", attack: "Attack") -> Callable[[], dict[str, Any]]:
        jammed = self.shaping_overrides(ex, attack, ex.window) if ex.window is not None else []
        t = ex.now()  # logged while the jammed shaping still holds
        ex.active.pop(attack.attack_id, None)
        if jammed:
            ex.reshape()
        t_end = ex.now()
        return lambda: {"t_unix": t, "shaping_until_unix": t_end}

    # ground truth ------------------------------------------------------------------------------
    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        plan, fol = ctx.plan, ctx.followed
        index = {x.name: x.index for x in plan.nodes}
        node = ctx.point_node
        n, W = len(plan.nodes), len(plan.windows)
        hit = np.zeros(fol.n_packets, dtype=bool)
        lo, c = fol.losses, fol.crossings()
        ok = lo.to_point >= 0
        lost_i, lost_j = node[lo.from_point], np.where(ok, node[np.maximum(lo.to_point, 0)], -1)
        for aw in windows:
            lost_keys, slow_keys = [], []  # (window * n + src) * n + dst of the jammed directions
            for win in plan.windows:
                links = {(lk.a, lk.b): lk for lk in win.links}
                for o in win.link_overrides:
                    if o.attack_id != aw.attack_id:
                        continue
                    key = (win.index * n + index[o.src]) * n + index[o.dst]
                    lost_keys.append(key)
                    lk = links.get((o.src, o.dst)) or links[(o.dst, o.src)]
                    if rate_or_loss_changed(lk.rate_mbps, lk.loss, o.rate_mbps, o.loss):
                        slow_keys.append(key)
            hit[lo.pid[ok & self._on(ctx, lo.t_s, lost_i, lost_j, aw, lost_keys, n, W)]] = True
            hit[c.pid[self._on(ctx, c.t_from, node[c.from_point], node[c.to_point], aw, slow_keys, n, W)]] = True
        return hit[fol.pid] if ctx.n else np.zeros(0, dtype=bool)

    @staticmethod
    def _on(ctx: "TruthContext", t: np.ndarray, i: np.ndarray, j: np.ndarray, aw: "AttackWindow", keys: list[int],
            n: int, W: int) -> np.ndarray:
        """Events at times t on direction i -> j inside the attack's [start, stop) on a listed
        direction of the plan window of t."""
        w = np.clip(np.floor((t - ctx.t0_unix) / ctx.plan.window_s), 0, W - 1).astype(np.int64)
        key = np.where((i >= 0) & (j >= 0), (w * n + i) * n + j, -1)
        return (t >= aw.start_unix) & (t < aw.stop_unix) & np.isin(key, np.asarray(keys, dtype=np.int64))
