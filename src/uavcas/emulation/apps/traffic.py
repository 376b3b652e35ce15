"""Benign traffic of a run, by the scenario's payload axis (`plan.scenario.payload`):

* `image`     nginx on every UAV, a curl loop per UAV on its BS (apps/client.py), unchanged;
* `telemetry` MAVLink v2 alone (apps/mavlink/): an autopilot endpoint per UAV, a ground
              station per BS on UDP 14550, no HTTP;
* `video`     MAVLink plus video: each UAV streams H.264 over RTP/UDP (ffmpeg, apps/video.py) to
              its BS's port 5600, where a sink counts it;
* `mixed`     MAVLink + video + images.
A hand-made plan without a scenario gets `image`.

`BenignTraffic.start_servers()` runs before t0 (servers must be listening when the clock
starts); `start_clients(t0)` right at t0 (an HTTP client skips the windows its UAV is
disconnected; a MAVLink UAV and its video keep sending into the void, as a radio would); `stop()` at the end,
returning a per-HTTP-client summary (the MAVLink endpoints log to logs/mavlink-<node>.jsonl).
"""

from __future__ import annotations

import signal
import sys
from collections import Counter
from dataclasses import asdict, dataclass
from pathlib import Path

from uavcas import seeding
from uavcas.emulation import kernel
from uavcas.vocabulary import MAVLINK_PAYLOADS

from . import client, images, mavlink, nginx, video
from .procs import Proc, spawn, wait_for

SERVER_READY_S = 15.0
MAVLINK_READY_S = 120.0  # loading Python + pymavlink in every namespace at once takes seconds
# The MAVLink endpoints' and the video senders' own deadlines lie this far past the run's end, and
# `stop()` ends them right after it: when 8 Python endpoints and 6 ffmpeg exited exactly at the end,
# their exit landed on the last attack stop and delayed it by 90-160 ms (quick blackhole+dos run).
APP_OVERRUN_S = 3.0
MAVLINK_GRACE_S = 10.0  # the endpoints' own deadline is the run's end; `timeout` kills them this much later


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
    def __init__(self, emu, plan, work_dir: Path, duration_s: float, *,
                 think_mean_s: float = client.THINK_MEAN_S, n_images: int = images.DEFAULT_COUNT,
                 stream_rates: mavlink.StreamRates = mavlink.StreamRates(),
                 video_kbps: int = video.BITRATE_KBPS, mavlink_signing: bool = False) -> None:
        self.emu, self.plan = emu, plan
        self.work, self.log_dir = work_dir, work_dir / "logs"
        self.duration_s = duration_s
        self.think_mean_s, self.n_images, self.stream_rates = think_mean_s, n_images, stream_rates
        self.payload = plan.scenario.payload if plan.scenario is not None else "image"
        self.http_on = self.payload in ("image", "mixed")
        self.mavlink_on = self.payload in MAVLINK_PAYLOADS
        self.video_on = self.payload in ("video", "mixed")
        self.video_kbps = video_kbps
        # MAVLink 2 signing on both ends, with the run's key (mavlink/signing.py); never the attacker's
        self.signing = mavlink.signing_spec(plan.seed, plan.config) if mavlink_signing else None
        self.uavs = [n for n in plan.nodes if n.kind == "uav"]
        self.bss = [n for n in plan.nodes if n.kind == "bs"]
        self.servers: list[Proc] = []
        self.clients: list[tuple[client.ClientSpec, Proc]] = []
        self.mavlink_procs: list[Proc] = []
        self.video_procs: list[Proc] = []
        self.t0_path = work_dir / "mavlink" / "t0"
        self.images: list[images.Image] = []

    def _start(self, node: str):
        return lambda argv, t, **kw: self.emu.popen(node, argv, t, **kw)

    def start_servers(self) -> None:
        if self.mavlink_on:
            self._start_mavlink()
        if self.video_on:
            self._start_video_sinks()
        if not self.http_on:
            return
        root = self.work / "images"
        self.images = images.generate(root, self.plan.seed, self.n_images)
        sites = []
        for n in self.uavs:
            site = nginx.NginxSite(n.name, n.ip, root, self.work / "nginx" / n.name)
            nginx.write_conf(site)
            self.servers.append(spawn(self._start(n.name), f"nginx-{n.name}", nginx.argv(site), self.log_dir,
                                      self.duration_s + 120))
            sites.append(site)

        def ready() -> bool:
            return all(nginx.listening(kernel.in_netns(self.emu.ns(s.node)), s) for s in sites)

        if not wait_for(ready, SERVER_READY_S, 0.05):
            dead = [p for p in self.servers if not p.alive()]
            why = dead[0].stderr().strip()[-300:] if dead else "not listening"
            raise RuntimeError(f"nginx did not start: {why}")

    def start_clients(self, t0_unix: float) -> None:
        if self.mavlink_on:
            mavlink.write_t0(self.t0_path, t0_unix)  # the endpoints, loaded before t0, start now
        if self.http_on:
            self._start_http(t0_unix)
        if self.video_on:
            self._start_video_senders()

    def client_specs(self, image_names: list[str], t0_unix: float) -> list[client.ClientSpec]:
        """One HTTP client per (BS, UAV) assignment, each on its own stream of the plan's seed."""
        offline: dict[str, list[int]] = {}
        for w in self.plan.windows:
            for u in self.plan.disconnected_uavs(w):
                offline.setdefault(u, []).append(w.index)
        return [client.ClientSpec(bs, uav, self.plan.node(uav).ip, tuple(image_names), self.duration_s,
                                  self.log_dir / f"http-{bs}-{uav}.tsv", seed=self.plan.seed, index=k,
                                  think_mean_s=self.think_mean_s, t0_unix=t0_unix,
                                  window_s=self.plan.window_s, offline_windows=tuple(offline.get(uav, ())))
                for k, (bs, uav) in enumerate(client.assignments([u.name for u in self.uavs],
                                                                 [b.name for b in self.bss]))]

    def _start_http(self, t0_unix: float) -> None:
        for spec in self.client_specs([img.name for img in self.images], t0_unix):
            bs, uav = spec.bs, spec.uav
            spec.log_path.parent.mkdir(parents=True, exist_ok=True)
            spec.log_path.write_text("")
            script = client.write_script(spec, self.work / "clients" / f"{bs}-{uav}.sh")
            proc = spawn(self._start(bs), f"client-{bs}-{uav}", ["bash", str(script)], self.log_dir,
                         self.duration_s + client.MAX_TIME_S + 5)
            self.clients.append((spec, proc))

    def _start_mavlink(self) -> None:
        """A ground station per BS and an autopilot per UAV, loaded and bound before t0; each waits
        for t0 (`t0_path`, written by start_clients) and then runs the plan's windows."""
        pairs = client.assignments([u.name for u in self.uavs], [b.name for b in self.bss])
        spec_dir = self.work / "mavlink"
        spec_dir.mkdir(parents=True, exist_ok=True)
        self.t0_path.unlink(missing_ok=True)
        run = [sys.executable, "-m", "uavcas.emulation.apps.mavlink"]
        app_s = self.duration_s + APP_OVERRUN_S
        timeout_s = mavlink.T0_WAIT_S + app_s + MAVLINK_GRACE_S
        for b in self.bss:
            if b.sysid is None:
                raise ValueError(f"{b.name} has no MAVLink system id in the plan")
            served = [mavlink.gcs_target(self.plan, uav) for bs, uav in pairs if bs == b.name]
            spec = mavlink.GcsSpec(name=b.name, sysid=b.sysid, rates=self.stream_rates, uavs=served,
                                   signing=self.signing,
                                   t0_path=self.t0_path, window_s=self.plan.window_s,
                                   n_windows=len(self.plan.windows), duration_s=app_s,
                                   log_path=self.log_dir / f"mavlink-{b.name}.jsonl")
            path = spec_dir / f"{b.name}.json"
            path.write_text(spec.model_dump_json())
            self.mavlink_procs.append(spawn(self._start(b.name), f"mavlink-{b.name}", run + ["gcs", str(path)],
                                            self.log_dir, timeout_s))
        for bs, uav in pairs:
            spec = mavlink.uav_spec(self.plan, uav, self.plan.node(bs).ip, None, app_s,
                                    self.log_dir / f"mavlink-{uav}.jsonl", t0_path=self.t0_path,
                                    signing=self.signing, gps_path=mavlink.gps.control_path(self.work, uav))
            path = spec_dir / f"{uav}.json"
            path.write_text(spec.model_dump_json())
            self.mavlink_procs.append(spawn(self._start(uav), f"mavlink-{uav}", run + ["uav", str(path)],
                                            self.log_dir, timeout_s))

        def ready() -> bool:  # every endpoint bound and waiting for t0
            return all(p.stdout().startswith("ready") for p in self.mavlink_procs)

        if not wait_for(ready, MAVLINK_READY_S, 0.05):
            bad = [p for p in self.mavlink_procs if not p.stdout().startswith("ready")]
            why = bad[0].stderr().strip()[-300:] or "not ready"
            raise RuntimeError(f"MAVLink endpoint {bad[0].name} did not start: {why}")

    def _video_spec(self, bs: str, k: int) -> video.VideoSpec:
        # one sink per BS receives every stream sent to it; each UAV's picture has its own seed,
        # drawn from the plan's seed into ffmpeg's range (a C int) whatever the plan's seed is
        seed = seeding.child_seed(self.plan.seed, "video-noise", k) % (video.MAX_SEED + 1)
        return video.VideoSpec(dst_ip=self.plan.node(bs).ip, log_path=self.log_dir / f"video-{bs}.jsonl",
                               duration_s=self.duration_s + APP_OVERRUN_S, seed=seed, bitrate_kbps=self.video_kbps)

    def _start_video_sinks(self) -> None:
        for b in self.bss:
            spec = self._video_spec(b.name, 0)
            self.video_procs.append(spawn(self._start(b.name), f"video-sink-{b.name}", video.sink_argv(spec),
                                          self.log_dir, spec.duration_s + 2 * video.SINK_SLACK_S))

        def ready() -> bool:  # every sink bound before a stream starts
            return all(video.READY in p.stdout() or not p.alive() for p in self.video_procs)

        if not wait_for(ready, SERVER_READY_S, 0.05) or not all(p.alive() for p in self.video_procs):
            bad = next((p for p in self.video_procs if not p.alive()), self.video_procs[0])
            raise RuntimeError(f"video sink {bad.name} did not start: {bad.stderr().strip()[-300:] or 'not ready'}")

    def _start_video_senders(self) -> None:
        """One ffmpeg per UAV from t0 to its BS, until `stop()` (its own `-t` lies past the end)."""
        pairs = client.assignments([u.name for u in self.uavs], [b.name for b in self.bss])
        for k, (bs, uav) in enumerate(pairs):
            spec = self._video_spec(bs, k)
            self.video_procs.append(spawn(self._start(uav), f"video-{uav}", video.sender_argv(spec), self.log_dir,
                                          spec.duration_s + video.SINK_SLACK_S))

    def stop(self) -> list[ClientSummary]:
        # the clients first (no fetch starts against a stopping server), then the rest; every
        # process of a group is signalled before any is waited for, so they wind down together
        for group in ([p for _, p in self.clients], self.video_procs + self.mavlink_procs + self.servers):
            for p in group:
                if p.popen.poll() is None:
                    try:
                        p.popen.send_signal(signal.SIGTERM)
                    except ProcessLookupError:
                        pass
            for p in group:
                p.stop(signal.SIGTERM, grace_s=2.0)
        return self.summary()

    def streams_summary(self) -> dict | None:
        """What the UDP applications did (run.json `streams`), from their own logs: per ground station
        the UAVs whose mission it uploaded and its commands' outcomes, per UAV the messages the GCS
        received by type; per video sink the bitrate each BS received. None for `image`."""
        if not (self.mavlink_on or self.video_on):
            return None
        out: dict = {"mavlink": {}, "video": {}}
        for b in self.bss if self.mavlink_on else ():
            path = self.log_dir / f"mavlink-{b.name}.jsonl"
            lines = mavlink.read_log(path) if path.exists() else []
            summary = next((e for e in reversed(lines) if e.get("event") == "summary"), None)
            results = Counter(e.get("result", "?") for e in lines if e.get("event") == "command_result")
            out["mavlink"][b.name] = {
                "uploaded": summary["uploaded"] if summary else None,
                "commands": dict(results),
                "received_by_uav": summary["received_by_uav"] if summary else None}
        for b in self.bss if self.video_on else ():
            path = self.log_dir / f"video-{b.name}.jsonl"
            try:
                sink = video.read_sink_log(path)
                out["video"][b.name] = {"datagrams": sink.datagrams, "rate_kbps": round(sink.rate_kbps, 1),
                                        "configured_kbps_per_stream": self.video_kbps}
            except (OSError, ValueError) as e:
                out["video"][b.name] = {"error": str(e).splitlines()[0]}
        return out

    def summary(self) -> list[ClientSummary]:
        out = []
        for spec, _ in self.clients:
            text = spec.log_path.read_text() if spec.log_path.exists() else ""
            fetches = client.parse_log(text)
            ok = [f for f in fetches if f.ok]
            out.append(ClientSummary(spec.bs, spec.uav, len(fetches), len(ok), len(fetches) - len(ok),
                                     sum(f.size_bytes for f in ok), client.skipped_windows(text)))
        return out
