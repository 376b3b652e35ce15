"""The `image` app: the paper's HTTP image fetches. One nginx per UAV serves a seeded image set
(`image.images`, `image.nginx`); on each UAV's BS a curl loop fetches from it at t0 on
(`image.client`), skipping the windows the plan has the UAV disconnected.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, ClassVar

from uavcas.emulation import kernel
from uavcas.emulation.apps.procs import spawn, wait_for

from ..base import SERVER_READY_S, AppContext, TrafficApp
from ..image import client, images, nginx
from ..registry import register


@dataclass
class ClientSummary:
    """One HTTP client's outcome (a row of run.json `http_clients`)."""

    bs: str
    uav: str
    fetches: int
    ok: int
    failed: int
    bytes: int
    skipped_windows: list[int]  # windows with no fetch: the UAV was disconnected (plan)

    def to_dict(self) -> dict:
        return asdict(self)


@register
class ImageApp(TrafficApp):
    name: ClassVar[str] = "image"
    summary: ClassVar[str] = "nginx on every UAV, a curl loop per UAV on its BS fetching seeded JPEG-sized images"

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        self.images: list[images.Image] = []
        self.clients: list[client.ClientSpec] = []

    def start_servers(self) -> None:
        ctx = self.ctx
        root = ctx.work_dir / "images"
        self.images = images.generate(root, ctx.plan.seed, ctx.options.n_images)
        sites = []
        for n in ctx.uavs:
            site = nginx.NginxSite(n.name, n.ip, root, ctx.work_dir / "nginx" / n.name)
            nginx.write_conf(site)
            self.procs.append(spawn(ctx.starter(n.name), f"nginx-{n.name}", nginx.argv(site), ctx.log_dir,
                                    ctx.duration_s + 120))
            sites.append(site)
        emu = ctx.emu

        def ready() -> bool:
            return all(nginx.listening(kernel.in_netns(emu.ns(s.node)), s) for s in sites)

        if not wait_for(ready, SERVER_READY_S, 0.05):
            dead = [p for p in self.procs if not p.alive()]
            why = dead[0].stderr().strip()[-300:] if dead else "not listening"
            raise RuntimeError(f"nginx did not start: {why}")

    def client_specs(self, image_names: list[str], t0_unix: float) -> list[client.ClientSpec]:
        """One HTTP client per (BS, UAV) assignment, each on its own stream of the plan's seed."""
        plan = self.ctx.plan
        offline: dict[str, list[int]] = {}
        for w in plan.windows:
            for u in plan.disconnected_uavs(w):
                offline.setdefault(u, []).append(w.index)
        return [client.ClientSpec(bs, uav, plan.node(uav).ip, tuple(image_names), self.ctx.duration_s,
                                  self.ctx.log_dir / f"http-{bs}-{uav}.tsv", seed=plan.seed, index=k,
                                  think_mean_s=self.ctx.options.think_mean_s, t0_unix=t0_unix,
                                  window_s=plan.window_s, offline_windows=tuple(offline.get(uav, ())))
                for k, (bs, uav) in enumerate(self.ctx.pairs)]

    def start_clients(self, t0_unix: float) -> None:
        ctx = self.ctx
        for spec in self.client_specs([img.name for img in self.images], t0_unix):
            bs, uav = spec.bs, spec.uav
            spec.log_path.parent.mkdir(parents=True, exist_ok=True)
            spec.log_path.write_text("")
            script = client.write_script(spec, ctx.work_dir / "clients" / f"{bs}-{uav}.sh")
            # clients stop before any server: no fetch starts against a stopping nginx
            self.early.append(spawn(ctx.starter(bs), f"client-{bs}-{uav}", ["bash", str(script)], ctx.log_dir,
                                    ctx.duration_s + client.MAX_TIME_S + 5))
            self.clients.append(spec)

    def summaries(self) -> list[ClientSummary]:
        out = []
        for spec in self.clients:
            text = spec.log_path.read_text() if spec.log_path.exists() else ""
            fetches = client.parse_log(text)
            ok = [f for f in fetches if f.ok]
            out.append(ClientSummary(spec.bs, spec.uav, len(fetches), len(ok), len(fetches) - len(ok),
                                     sum(f.size_bytes for f in ok), client.skipped_windows(text)))
        return out

    def client_summaries(self) -> list[dict[str, Any]]:
        return [s.to_dict() for s in self.summaries()]
