"""The `video` app: each UAV streams H.264 over RTP/UDP (ffmpeg, `uavcas.traffic.video`) from t0
to its BS's port 5600, where a sink (bound before t0) counts what arrives.
"""

from __future__ import annotations

from typing import Any, ClassVar

from uavcas import seeding
from uavcas.emulation.apps.procs import spawn, wait_for
from uavcas.traffic import video

from ..base import APP_OVERRUN_S, SERVER_READY_S, TrafficApp
from ..registry import register


@register
class VideoApp(TrafficApp):
    name: ClassVar[str] = "video"
    summary: ClassVar[str] = "H.264 over RTP/UDP per UAV (ffmpeg, constant bitrate) to a counting sink on its BS"

    def spec(self, bs: str, k: int) -> video.VideoSpec:
        """The stream of pair k to `bs` (k = 0: the BS's sink). One sink per BS receives every
        stream sent to it; each UAV's picture has its own seed, drawn from the plan's seed into
        ffmpeg's range (a C int) whatever the plan's seed is."""
        ctx = self.ctx
        seed = seeding.child_seed(ctx.plan.seed, "video-noise", k) % (video.MAX_SEED + 1)
        return video.VideoSpec(dst_ip=ctx.plan.node(bs).ip, log_path=ctx.log_dir / f"video-{bs}.jsonl",
                               duration_s=ctx.duration_s + APP_OVERRUN_S, seed=seed,
                               bitrate_kbps=ctx.options.video_kbps)

    def start_servers(self) -> None:
        ctx = self.ctx
        sinks = []
        for b in ctx.bss:
            spec = self.spec(b.name, 0)
            sinks.append(spawn(ctx.starter(b.name), f"video-sink-{b.name}", video.sink_argv(spec),
                               ctx.log_dir, spec.duration_s + 2 * video.SINK_SLACK_S))
        self.procs.extend(sinks)

        def ready() -> bool:  # every sink bound before a stream starts
            return all(video.READY in p.stdout() or not p.alive() for p in sinks)

        if not wait_for(ready, SERVER_READY_S, 0.05) or not all(p.alive() for p in sinks):
            bad = next((p for p in sinks if not p.alive()), sinks[0])
            raise RuntimeError(f"video sink {bad.name} did not start: {bad.stderr().strip()[-300:] or 'not ready'}")

    def start_clients(self, t0_unix: float) -> None:
        """One ffmpeg per UAV from t0 to its BS, until the stop (its own `-t` lies past the end)."""
        ctx = self.ctx
        for k, (bs, uav) in enumerate(ctx.pairs):
            spec = self.spec(bs, k)
            self.procs.append(spawn(ctx.starter(uav), f"video-{uav}", video.sender_argv(spec), ctx.log_dir,
                                    spec.duration_s + video.SINK_SLACK_S))

    def streams(self) -> dict[str, Any]:
        """Per BS sink: the datagrams and bitrate it received (from its own log)."""
        out: dict[str, Any] = {}
        for b in self.ctx.bss:
            path = self.ctx.log_dir / f"video-{b.name}.jsonl"
            try:
                sink = video.read_sink_log(path)
                out[b.name] = {"datagrams": sink.datagrams, "rate_kbps": round(sink.rate_kbps, 1),
                               "configured_kbps_per_stream": self.ctx.options.video_kbps}
            except (OSError, ValueError) as e:
                out[b.name] = {"error": str(e).splitlines()[0]}
        return out
