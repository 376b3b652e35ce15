"""Optional video downlink: a UAV streams H.264 over RTP/UDP to its BS, which counts and discards it.

Sender: ffmpeg encodes a seeded synthetic picture (lavfi `testsrc2` under a temporal `noise`
whose `all_seed` is the spec's seed: the same seed gives the same picture sequence, and the
noise keeps the encoder busy the way a real camera's sensor noise does, so the CBR rate control
spends real bits instead of padding) with libx264 at a constant bitrate, paced in real time
(`-re`), and sends it as RTP (RFC 6184, packetization mode 1: single NAL units and FU-A
fragments, payload type 96) to the BS. Bounded by its own `-t` and the `timeout` the core wraps
around every tool. No audio, no display, no network beyond the destination.

Sink: a small Python UDP receiver (`python -m uavcas.traffic.video sink ...`) rather than
an ffmpeg receiver: ffmpeg needs an SDP file to receive plain RTP, would decode (CPU per BS for
nothing) and reports no per-second byte counts, whereas the sink's counts are exact, one JSON
line per 1 s bin of the epoch clock (bins without traffic included, so an outage shows as zeros),
and it checks each datagram's RTP/H.264 framing. Its only other job is to have the port open,
so no ICMP port-unreachable appears in the captures. (ffmpeg prints the stream's SDP on stdout,
the sender's .out file: enough to play a stream by hand.) Bounded by `--seconds`; SIGTERM/SIGINT end
it early after writing the current bin and a summary line.

No RTCP: companion-computer video pipelines (gstreamer `rtph264pay ! udpsink port=5600`, the
ArduPilot wiki's video streaming recipes) send bare RTP, and ffmpeg's default RTCP sender
reports would go to port + 1, where nothing listens (`-rtpflags skip_rtcp`).

Run: python -m uavcas.traffic.video sink --bind IP --port 5600 --seconds S --log F
"""

from __future__ import annotations

import argparse
import ipaddress
import json
import math
import signal
import socket
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from uavcas import seeding

# QGroundControl's "UDP h.264 Video Stream" listens on 0.0.0.0:5600 by default (udpUrl in
# QGC's src/Settings/Video.SettingsGroup.json) and ArduPilot's companion video recipes send there.
PORT = 5600
# 640x360 at 30 fps: the "SD" downlink of small UAVs (the full-HD camera records on board).
WIDTH_PX, HEIGHT_PX, FPS = 640, 360, 30
# The Kush gauge (pixels x fps x motion factor x 0.07 bit) gives 0.48 Mbit/s for this format at
# low motion and 0.97 Mbit/s at medium motion: 500 kbit/s, the low-motion figure (a survey UAV's
# camera moves slowly). The twin's BS links plan 3-4 Mbit/s in the quick scenarios and carry 2-3
# UAVs each plus their image fetches: with 1000 kbit/s streams beside the images they were full and
# MAVLink lost 30-60 % of its messages in the queues (a 6-UAV mixed run, seed 14). `uavcas run --video-kbps` sets it.
BITRATE_KBPS = 500
GOP_S = 1.0  # one IDR per second: a receiver joining or losing packets recovers within 1 s
# VBV of half a second: tight enough that every 1 s bin carries about the configured rate (an
# I frame may not borrow much from the following frames), loose enough for x264 to hold quality.
VBV_S = 0.5
# Largest RTP datagram (RTP header included, ffmpeg's pkt_size). The fabric's veths keep the
# default 1500 B MTU (nothing in emulation sets one); 1200 leaves room for IP/UDP (28 B) and any
# encapsulation, as WebRTC and most RTP stacks do.
PKT_SIZE_BYTES = 1200
MAX_PKT_SIZE_BYTES = 1500 - 20 - 8  # one unfragmented UDP datagram on a 1500 B MTU
PAYLOAD_TYPE = 96  # first dynamic RTP payload type (RFC 3551), what ffmpeg and gstreamer use
NOISE_STRENGTH = 20  # of 100: visible sensor-like grain, not a snow screen
# ultrafast: 0.044 s of CPU per stream second at 640x360/30 fps, 1000 kbit/s here (veryfast:
# 0.10 s) and 20 UAVs share the host with the emulation; the traffic's shape (CBR, GOP, packet
# sizes) is what matters, not the picture quality.
X264_PRESET = "ultrafast"
READY = "ready"  # printed by the sink once bound
SINK_SLACK_S = 3.0  # the sink outlives the sender by this much (ffmpeg start-up, last packets)
RCVBUF_BYTES = 1 << 20  # an IDR burst arrives within a millisecond; do not drop it at the BS
MAX_SEED = 2**31 - 1  # the noise filter's seed is a C int


@dataclass(frozen=True)
class VideoSpec:
    dst_ip: str  # the BS's address (the sink binds it)
    log_path: Path  # the sink's JSON lines log
    duration_s: float
    seed: int
    port: int = PORT
    bitrate_kbps: int = BITRATE_KBPS  # kbit/s = 1000 bit/s of H.264 (what `-b:v` counts)
    width_px: int = WIDTH_PX
    height_px: int = HEIGHT_PX
    fps: int = FPS
    gop_s: float = GOP_S
    pkt_size_bytes: int = PKT_SIZE_BYTES

    def __post_init__(self) -> None:
        try:
            ipaddress.IPv4Address(self.dst_ip)
        except ValueError:
            raise ValueError(f"video: dst_ip {self.dst_ip!r} is not an IPv4 address") from None
        if not 1 <= self.port <= 65535:
            raise ValueError(f"video: port {self.port} is not in 1..65535")
        if not self.bitrate_kbps > 0:
            raise ValueError(f"video: bitrate_kbps {self.bitrate_kbps} must be > 0")
        if not (math.isfinite(self.duration_s) and self.duration_s > 0):
            raise ValueError(f"video: duration_s {self.duration_s} must be > 0")
        if not 0 <= self.seed <= MAX_SEED:
            raise ValueError(f"video: seed {self.seed} is not in 0..{MAX_SEED} (ffmpeg noise seed)")
        # yuv420p halves chroma both ways: odd sizes are rejected by libx264
        for name, v in (("width_px", self.width_px), ("height_px", self.height_px)):
            if v < 16 or v % 2:
                raise ValueError(f"video: {name} {v} must be even and >= 16")
        if not 1 <= self.fps <= 120:
            raise ValueError(f"video: fps {self.fps} is not in 1..120")
        if not (math.isfinite(self.gop_s) and self.gop_s > 0):
            raise ValueError(f"video: gop_s {self.gop_s} must be > 0")
        if not 100 <= self.pkt_size_bytes <= MAX_PKT_SIZE_BYTES:
            raise ValueError(f"video: pkt_size_bytes {self.pkt_size_bytes} is not in 100..{MAX_PKT_SIZE_BYTES}")

    @property
    def gop_frames(self) -> int:
        return max(1, round(self.gop_s * self.fps))

    @property
    def ssrc(self) -> int:
        """Seeded RTP SSRC (ffmpeg would draw a random one): a rerun of a seed has the same stream ids."""
        return _stream_ids(self.seed)[0]

    @property
    def first_seq(self) -> int:
        """Seeded first RTP sequence number (ffmpeg would draw a random one)."""
        return _stream_ids(self.seed)[1]


def _stream_ids(seed: int) -> tuple[int, int]:
    rng = seeding.generator(seed, "video-rtp")
    return int(rng.integers(1, 2**31)), int(rng.integers(0, 2**16))  # ffmpeg's -ssrc is a C int


def _source_args(spec: VideoSpec) -> list[str]:
    graph = (f"testsrc2=size={spec.width_px}x{spec.height_px}:rate={spec.fps},"
             f"noise=alls={NOISE_STRENGTH}:allf=t:all_seed={spec.seed},format=yuv420p")
    # One filter thread: the noise filter works in slices, one thread keeps its output exact.
    return ["-filter_threads", "1", "-f", "lavfi", "-i", graph]


def _encoder_args(spec: VideoSpec) -> list[str]:
    rate = f"{spec.bitrate_kbps}k"
    vbv = f"{max(1, round(spec.bitrate_kbps * VBV_S))}k"
    return ["-an", "-c:v", "libx264", "-preset", X264_PRESET, "-tune", "zerolatency",
            # one thread: a bounded CPU share per UAV, and bit-exact output for a seed
            "-threads", "1",
            # fixed GOP, no scene-cut IDRs: the key frame cadence is the spec's, not the content's
            "-g", str(spec.gop_frames), "-keyint_min", str(spec.gop_frames), "-sc_threshold", "0",
            # CBR: x264's HRD model in CBR mode pads up to the rate (filler) instead of undershooting
            "-b:v", rate, "-minrate", rate, "-maxrate", rate, "-bufsize", vbv,
            "-x264-params", "nal-hrd=cbr"]


def _common_args() -> list[str]:
    # -nostdin: never read the terminal (spawned with stdin at /dev/null anyway);
    # warnings only: the err file stays small for a long run
    return ["ffmpeg", "-hide_banner", "-nostdin", "-nostats", "-loglevel", "warning"]


def sender_argv(spec: VideoSpec) -> list[str]:
    """The UAV side: ffmpeg, real-time paced, RTP to dst_ip:port for duration_s."""
    url = f"rtp://{spec.dst_ip}:{spec.port}?pkt_size={spec.pkt_size_bytes}"
    return [*_common_args(), "-re", *_source_args(spec), *_encoder_args(spec),
            "-t", f"{spec.duration_s:g}",
            "-f", "rtp", "-payload_type", str(PAYLOAD_TYPE), "-rtpflags", "skip_rtcp",
            "-ssrc", str(spec.ssrc), "-seq", str(spec.first_seq), url]


def file_argv(spec: VideoSpec, out_path: Path, seconds: float) -> list[str]:
    """The same source and encoder as `sender_argv`, unpaced, to a raw H.264 (Annex B) file."""
    if not (math.isfinite(seconds) and seconds > 0):
        raise ValueError(f"video: seconds {seconds} must be > 0")
    return [*_common_args(), "-y", *_source_args(spec), *_encoder_args(spec),
            "-t", f"{seconds:g}", "-f", "h264", str(out_path)]


def sink_argv(spec: VideoSpec, python: str = sys.executable, seconds: float | None = None) -> list[str]:
    """The BS side: this module's sink on dst_ip:port, by default for duration_s + SINK_SLACK_S."""
    secs = spec.duration_s + SINK_SLACK_S if seconds is None else seconds
    return [python, "-m", "uavcas.traffic.video", "sink", "--bind", spec.dst_ip,
            "--port", str(spec.port), "--seconds", f"{secs:g}", "--log", str(spec.log_path),
            "--payload-type", str(PAYLOAD_TYPE)]


def rtp_h264_ok(datagram: bytes, payload_type: int = PAYLOAD_TYPE) -> bool:
    """RTP version 2 with `payload_type`, carrying an H.264 packetization-mode-1 unit (RFC 6184):
    a single NAL unit (types 1-23), a STAP-A (24) or an FU-A (28), forbidden bit clear."""
    if len(datagram) < 13 or datagram[0] >> 6 != 2 or datagram[1] & 0x7F != payload_type:
        return False
    head = 12 + 4 * (datagram[0] & 0x0F)  # CSRC list
    if datagram[0] & 0x10:  # header extension: 4 B + length words
        if len(datagram) < head + 4:
            return False
        head += 4 + 4 * int.from_bytes(datagram[head + 2:head + 4], "big")
    if len(datagram) <= head:
        return False
    nal = datagram[head]
    return not nal & 0x80 and (1 <= nal & 0x1F <= 24 or nal & 0x1F == 28)


@dataclass(frozen=True)
class SinkBin:
    t_unix: int  # bin [t_unix, t_unix + 1) of the epoch clock
    datagrams: int
    payload_bytes: int  # UDP payload (RTP header included)
    not_rtp_h264: int  # datagrams failing `rtp_h264_ok`
    max_datagram_bytes: int


@dataclass(frozen=True)
class SinkSummary:
    bins: tuple[SinkBin, ...]
    first_unix: float | None  # first/last datagram; None: nothing received
    last_unix: float | None
    stopped_by: str | None = None  # "deadline", "signal"; None: no summary line (sink killed)

    @property
    def datagrams(self) -> int:
        return sum(b.datagrams for b in self.bins)

    @property
    def payload_bytes(self) -> int:
        return sum(b.payload_bytes for b in self.bins)

    @property
    def not_rtp_h264(self) -> int:
        return sum(b.not_rtp_h264 for b in self.bins)

    @property
    def max_datagram_bytes(self) -> int:
        return max((b.max_datagram_bytes for b in self.bins), default=0)

    @property
    def active_s(self) -> float:
        return 0.0 if self.first_unix is None or self.last_unix is None else self.last_unix - self.first_unix

    @property
    def rate_kbps(self) -> float:
        """Mean received rate between the first and the last datagram (0 for under two datagrams' span)."""
        return self.payload_bytes * 8 / self.active_s / 1000 if self.active_s > 0 else 0.0

    def per_second_kbps(self) -> list[tuple[int, float]]:
        return [(b.t_unix, b.payload_bytes * 8 / 1000) for b in self.bins]

    def steady_rate_kbps(self, skip_s: float = 1.0) -> float:
        """Mean rate over the whole 1 s bins lying in [first datagram + skip_s, last datagram]:
        the encoder's start (first IDR, VBV filling) and the partial edge bins are left out."""
        if self.first_unix is None or self.last_unix is None:
            raise ValueError("video: the sink received nothing")
        full = [b for b in self.bins if b.t_unix >= self.first_unix + skip_s and b.t_unix + 1 <= self.last_unix]
        if not full:
            raise ValueError(f"video: no whole 1 s bin after skipping {skip_s:g} s of a {self.active_s:.2f} s stream")
        return sum(b.payload_bytes for b in full) * 8 / len(full) / 1000


def read_sink_log(path: Path) -> SinkSummary:
    """Parse a sink log. Without its summary line (sink killed) the first/last datagram times
    fall back to the edges of the first/last non-empty bins."""
    bins: list[SinkBin] = []
    first = last = stopped_by = None
    have_summary = False
    for n, line in enumerate(Path(path).read_text().splitlines(), 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
            if "summary" in rec:
                first, last = (None if rec[k] is None else float(rec[k]) for k in ("first_unix", "last_unix"))
                have_summary = True
                stopped_by = str(rec["stopped_by"])
            else:
                bins.append(SinkBin(int(rec["t_unix"]), int(rec["datagrams"]), int(rec["payload_bytes"]),
                                    int(rec["not_rtp_h264"]), int(rec["max_datagram_bytes"])))
        except (ValueError, KeyError, TypeError) as e:
            raise ValueError(f"video: {path}:{n}: not a sink log line ({e})") from None
    if not have_summary:
        busy = [b.t_unix for b in bins if b.datagrams]
        first, last = (float(busy[0]), float(busy[-1] + 1)) if busy else (None, None)
    return SinkSummary(tuple(bins), first, last, stopped_by)


class _Bin:
    def __init__(self, t_unix: int) -> None:
        self.t_unix, self.datagrams, self.payload_bytes, self.bad, self.max_bytes = t_unix, 0, 0, 0, 0

    def line(self) -> str:
        return json.dumps({"t_unix": self.t_unix, "datagrams": self.datagrams, "payload_bytes": self.payload_bytes,
                           "not_rtp_h264": self.bad, "max_datagram_bytes": self.max_bytes})


def sink(bind: str, port: int, seconds: float, log_path: Path, payload_type: int = PAYLOAD_TYPE) -> SinkSummary:
    """Receive until `seconds` pass or SIGTERM/SIGINT; one log line per 1 s bin, then a summary."""
    stop = False

    def on_signal(signum, frame):  # a flag, not an exception: never cut a log line in half
        nonlocal stop
        stop = True

    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, on_signal)
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RCVBUF_BYTES)
    s.bind((bind, port))
    print(READY, flush=True)  # the runner starts the streams once every sink is bound
    log_path.parent.mkdir(parents=True, exist_ok=True)
    end = time.monotonic() + seconds
    first = last = None
    cur = _Bin(int(time.time()))
    with open(log_path, "w", buffering=1) as log:  # line-buffered: a killed sink keeps its bins
        while not stop and (left := end - time.monotonic()) > 0:
            now = time.time()
            # wake at the bin edge (zero bins are logged too) and often enough to see a signal
            s.settimeout(max(0.001, min(left, cur.t_unix + 1 - now, 0.2)))
            try:
                data = s.recv(65535)
                now = time.time()
            except (socket.timeout, InterruptedError):
                data, now = None, time.time()
            while int(now) > cur.t_unix:
                log.write(cur.line() + "\n")
                cur = _Bin(cur.t_unix + 1)
            if data is not None:
                first = now if first is None else first
                last = now
                cur.datagrams += 1
                cur.payload_bytes += len(data)
                cur.max_bytes = max(cur.max_bytes, len(data))
                cur.bad += not rtp_h264_ok(data, payload_type)
        log.write(cur.line() + "\n")
        log.write(json.dumps({"summary": True, "first_unix": first, "last_unix": last,
                              "stopped_by": "signal" if stop else "deadline"}) + "\n")
    s.close()
    return read_sink_log(log_path)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    k = sub.add_parser("sink", help="count and discard an RTP stream, one JSON line per second")
    k.add_argument("--bind", default="0.0.0.0")
    k.add_argument("--port", type=int, default=PORT)
    k.add_argument("--seconds", type=float, required=True)
    k.add_argument("--log", type=Path, required=True)
    k.add_argument("--payload-type", type=int, default=PAYLOAD_TYPE)
    a = ap.parse_args(argv)
    if not (math.isfinite(a.seconds) and a.seconds > 0):
        ap.error(f"--seconds {a.seconds} must be > 0")
    if not 1 <= a.port <= 65535:
        ap.error(f"--port {a.port} is not in 1..65535")
    try:
        sink(a.bind, a.port, a.seconds, a.log, a.payload_type)
    except OSError as e:
        sys.exit(f"video sink: {a.bind}:{a.port}: {e.strerror or e}")


if __name__ == "__main__":
    main()
