"""Benign traffic of a run: nginx on every UAV, curl loops on the BSs, optional telemetry.

`BenignTraffic.start_servers()` runs before t0 (servers must be listening when the clock
starts); `start_clients(t0)` right at t0 (a client skips the windows its UAV is disconnected); `stop()` at the end, returning a per-client summary.
"""

from __future__ import annotations

import signal
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

from uavcas.emulation import kernel

from . import client, images, nginx, telemetry
from .procs import Proc, spawn, wait_for

SERVER_READY_S = 15.0


@dataclass
class ClientSummary:
    bs: str
    uav: str
    fetches: int
    ok: int
    failed: int
    bytes: int
    skipped_windows: list[int]  # windows with no fetch: the UAV was disconnected (plan)

    def to_dict(self) -> dict:
        return asdict(self)


class BenignTraffic:
    def __init__(self, emu, plan, work_dir: Path, duration_s: float, *, telemetry_on: bool = False,
                 think_mean_s: float = client.THINK_MEAN_S, n_images: int = images.DEFAULT_COUNT) -> None:
        self.emu, self.plan = emu, plan
        self.work, self.log_dir = work_dir, work_dir / "logs"
        self.duration_s = duration_s
        self.telemetry_on, self.think_mean_s, self.n_images = telemetry_on, think_mean_s, n_images
        self.uavs = [n for n in plan.nodes if n.kind == "uav"]
        self.bss = [n for n in plan.nodes if n.kind == "bs"]
        self.servers: list[Proc] = []
        self.clients: list[tuple[client.ClientSpec, Proc]] = []
        self.others: list[Proc] = []
        self.images: list[images.Image] = []

    def _start(self, node: str):
        return lambda argv, t, **kw: self.emu.popen(node, argv, t, **kw)

    def start_servers(self) -> None:
        root = self.work / "images"
        self.images = images.generate(root, self.plan.seed, self.n_images)
        sites = []
        for n in self.uavs:
            site = nginx.NginxSite(n.name, n.ip, root, self.work / "nginx" / n.name)
            nginx.write_conf(site)
            self.servers.append(spawn(self._start(n.name), f"nginx-{n.name}", nginx.argv(site), self.log_dir,
                                      self.duration_s + 120))
            sites.append(site)
        if self.telemetry_on:
            for b in self.bss:
                argv = [sys.executable, "-m", "uavcas.emulation.apps.telemetry", "sink",
                        "--seconds", str(self.duration_s + 10)]
                self.others.append(spawn(self._start(b.name), f"telemetry-sink-{b.name}", argv, self.log_dir,
                                         self.duration_s + 20))

        def ready() -> bool:
            return all(nginx.listening(kernel.in_netns(self.emu.ns(s.node)), s) for s in sites)

        if not wait_for(ready, SERVER_READY_S, 0.05):
            dead = [p for p in self.servers if not p.alive()]
            why = dead[0].stderr().strip()[-300:] if dead else "not listening"
            raise RuntimeError(f"nginx did not start: {why}")

    def start_clients(self, t0_unix: float) -> None:
        names = [img.name for img in self.images]
        offline: dict[str, list[int]] = {}
        for w in self.plan.windows:
            for u in self.plan.disconnected_uavs(w):
                offline.setdefault(u, []).append(w.index)
        for k, (bs, uav) in enumerate(client.assignments([u.name for u in self.uavs], [b.name for b in self.bss])):
            spec = client.ClientSpec(bs, uav, self.plan.node(uav).ip, tuple(names), self.duration_s,
                                     self.log_dir / f"http-{bs}-{uav}.tsv", seed=self.plan.seed * 1000 + k,
                                     think_mean_s=self.think_mean_s, t0_unix=t0_unix,
                                     window_s=self.plan.window_s, offline_windows=tuple(offline.get(uav, ())))
            spec.log_path.parent.mkdir(parents=True, exist_ok=True)
            spec.log_path.write_text("")
            script = client.write_script(spec, self.work / "clients" / f"{bs}-{uav}.sh")
            proc = spawn(self._start(bs), f"client-{bs}-{uav}", ["bash", str(script)], self.log_dir,
                         self.duration_s + client.MAX_TIME_S + 5)
            self.clients.append((spec, proc))
        if self.telemetry_on:
            for i, u in enumerate(self.uavs):
                bs = self.bss[i % len(self.bss)]
                argv = [sys.executable, "-m", "uavcas.emulation.apps.telemetry", "send", "--dst", bs.ip,
                        "--sysid", str(i + 1), "--seconds", str(self.duration_s)]
                self.others.append(spawn(self._start(u.name), f"telemetry-{u.name}", argv, self.log_dir,
                                         self.duration_s + 10))

    def stop(self) -> list[ClientSummary]:
        for _, p in self.clients:
            p.stop(signal.SIGTERM, grace_s=2.0)
        for p in self.others + self.servers:
            p.stop(signal.SIGTERM, grace_s=2.0)
        return self.summary()

    def summary(self) -> list[ClientSummary]:
        out = []
        for spec, _ in self.clients:
            text = spec.log_path.read_text() if spec.log_path.exists() else ""
            fetches = client.parse_log(text)
            ok = [f for f in fetches if f.ok]
            out.append(ClientSummary(spec.bs, spec.uav, len(fetches), len(ok), len(fetches) - len(ok),
                                     sum(f.size_bytes for f in ok), client.skipped_windows(text)))
        return out
