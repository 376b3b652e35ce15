"""The video downlink app: argv, RTP checks, the sink and its log, and real ffmpeg streams on 127.0.0.1."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

from uavcas.traffic import video
from uavcas.traffic.apps.video import VideoApp
from uavcas.traffic.base import AppContext
from uavcas.traffic.video import VideoSpec
from uavcas.twin.plan import plan

SRC = Path(video.__file__).resolve().parents[3]  # this checkout's src/, for the sink subprocesses


def _has_libx264() -> bool:
    if shutil.which("ffmpeg") is None:
        return False
    out = subprocess.run(["ffmpeg", "-hide_banner", "-encoders"], capture_output=True, text=True, timeout=30)
    return "libx264" in out.stdout


needs_ffmpeg = pytest.mark.skipif(not _has_libx264(), reason="ffmpeg with libx264 not installed (scripts/setup.sh)")


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}


def _free_udp_pair() -> int:
    """A UDP port P with P + 1 free too (P + 1 is watched for RTCP)."""
    for _ in range(50):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as a:
            a.bind(("127.0.0.1", 0))
            p = a.getsockname()[1]
            if p >= 65535:
                continue
            try:
                with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as b:
                    b.bind(("127.0.0.1", p + 1))
            except OSError:
                continue
        return p
    raise RuntimeError("no free UDP port pair on 127.0.0.1")


def _spec(tmp_path: Path, **kw) -> VideoSpec:
    base = dict(dst_ip="127.0.0.1", log_path=tmp_path / "sink.jsonl", duration_s=9.0, seed=11)
    return VideoSpec(**{**base, **kw})


def _rtp(pt: int = 96, nal: int = 0x7C, version: int = 2, cc: int = 0, ext_words: int | None = None) -> bytes:
    b0 = (version << 6) | cc | (0x10 if ext_words is not None else 0)
    head = struct.pack("!BBHII", b0, pt, 1, 2, 3) + b"\0\0\0\0" * cc
    if ext_words is not None:
        head += struct.pack("!HH", 0xBEDE, ext_words) + b"\0" * 4 * ext_words
    return head + bytes([nal]) + b"\x85payload"


def test_defaults_and_units(tmp_path):
    s = _spec(tmp_path)
    assert (s.port, s.bitrate_kbps, s.width_px, s.height_px, s.fps) == (5600, 500, 640, 360, 30)
    assert s.gop_frames == 30 and s.pkt_size_bytes == 1200 <= video.MAX_PKT_SIZE_BYTES
    assert _spec(tmp_path, fps=25, gop_s=2.0).gop_frames == 50


def test_sender_argv_is_seeded_and_carries_the_settings(tmp_path):
    s = _spec(tmp_path, bitrate_kbps=800, port=5700, seed=1234)
    argv = video.sender_argv(s)
    assert argv == video.sender_argv(_spec(tmp_path, bitrate_kbps=800, port=5700, seed=1234))
    assert argv[0] == "ffmpeg" and "-re" in argv and argv[-1] == "rtp://127.0.0.1:5700?pkt_size=1200"
    graph = argv[argv.index("-i") + 1]
    assert graph.startswith("testsrc2=size=640x360:rate=30,") and "all_seed=1234" in graph and "allf=t" in graph
    for opt, val in (("-b:v", "800k"), ("-maxrate", "800k"), ("-minrate", "800k"), ("-bufsize", "400k"),
                     ("-g", "30"), ("-threads", "1"), ("-t", "9"), ("-payload_type", "96"),
                     ("-rtpflags", "skip_rtcp"), ("-f", "lavfi"), ("-c:v", "libx264"),
                     ("-ssrc", str(s.ssrc)), ("-seq", str(s.first_seq))):
        assert val in [argv[i + 1] for i, a in enumerate(argv) if a == opt], (opt, val)
    assert "-an" in argv and "nal-hrd=cbr" in argv
    other = video.sender_argv(_spec(tmp_path, bitrate_kbps=800, port=5700, seed=1235))
    assert other != argv and "all_seed=1235" in other[other.index("-i") + 1]
    assert (s.ssrc, s.first_seq) != (_spec(tmp_path, seed=1235).ssrc, _spec(tmp_path, seed=1235).first_seq)
    assert 1 <= s.ssrc < 2**31 and 0 <= s.first_seq < 2**16
    f = video.file_argv(s, tmp_path / "a.h264", 1.5)
    assert "-re" not in f and f[-3:] == ["-f", "h264", str(tmp_path / "a.h264")] and "1.5" in f
    assert f[f.index("-i") + 1] == graph and "rtp" not in " ".join(f)


def test_sink_argv(tmp_path):
    s = _spec(tmp_path, port=5701, duration_s=10)
    argv = video.sink_argv(s, python="/venv/bin/python")
    assert argv == ["/venv/bin/python", "-m", "uavcas.traffic.video", "sink", "--bind", "127.0.0.1",
                    "--port", "5701", "--seconds", "13", "--log", str(tmp_path / "sink.jsonl"), "--payload-type", "96"]
    assert video.sink_argv(s, python="py", seconds=4.5)[argv.index("--seconds") + 1] == "4.5"


@pytest.mark.parametrize("kw, needle", [
    (dict(dst_ip="10.0.0.300"), "dst_ip"), (dict(dst_ip="bs0"), "dst_ip"), (dict(port=0), "port"),
    (dict(port=70000), "port"), (dict(bitrate_kbps=0), "bitrate_kbps"), (dict(duration_s=0), "duration_s"),
    (dict(duration_s=float("nan")), "duration_s"), (dict(seed=-1), "seed"), (dict(seed=2**31), "seed"),
    (dict(width_px=641), "width_px"), (dict(height_px=8), "height_px"), (dict(fps=0), "fps"),
    (dict(gop_s=0.0), "gop_s"), (dict(pkt_size_bytes=1473), "pkt_size_bytes"), (dict(pkt_size_bytes=50), "pkt_size")])
def test_bad_spec_is_a_one_line_error(tmp_path, kw, needle):
    with pytest.raises(ValueError) as e:
        _spec(tmp_path, **kw)
    assert needle in str(e.value) and "\n" not in str(e.value)


def test_bad_file_seconds(tmp_path):
    with pytest.raises(ValueError, match="seconds"):
        video.file_argv(_spec(tmp_path), tmp_path / "x.h264", 0)


def test_rtp_h264_check():
    assert video.rtp_h264_ok(_rtp(nal=0x7C))  # FU-A (28), NRI 3
    assert video.rtp_h264_ok(_rtp(nal=0x65))  # IDR slice
    assert video.rtp_h264_ok(_rtp(nal=0x18))  # STAP-A
    assert video.rtp_h264_ok(_rtp(nal=0x41, cc=2))  # CSRCs skipped
    assert video.rtp_h264_ok(_rtp(nal=0x67, ext_words=1))  # header extension skipped
    assert not video.rtp_h264_ok(_rtp(nal=0x7C, ext_words=None, cc=0)[:12])  # no payload
    assert not video.rtp_h264_ok(_rtp(version=1))
    assert not video.rtp_h264_ok(_rtp(pt=97))
    assert video.rtp_h264_ok(_rtp(pt=97), payload_type=97)
    assert not video.rtp_h264_ok(_rtp(pt=96 | 0x80, nal=0x00))  # marker set, NAL type 0
    assert video.rtp_h264_ok(_rtp(pt=96 | 0x80, nal=0x41))  # the marker bit is not the payload type
    for nal in (0x19, 0x1A, 0x1B, 0x1D, 0x1F, 0xFC):  # STAP-B, MTAP16/24, FU-B, reserved, forbidden bit
        assert not video.rtp_h264_ok(_rtp(nal=nal)), hex(nal)
    assert not video.rtp_h264_ok(_rtp(nal=0x41, ext_words=3)[:20])  # extension runs past the end
    assert not video.rtp_h264_ok(b"\x80\x60")


def _bin(t: int, n: int, b: int, bad: int = 0, mx: int = 1200) -> str:
    return json.dumps({"t_unix": t, "datagrams": n, "payload_bytes": b, "not_rtp_h264": bad, "max_datagram_bytes": mx})


def test_read_sink_log(tmp_path):
    log = tmp_path / "s.jsonl"
    lines = [_bin(100, 0, 0, mx=0), _bin(101, 50, 40_000), _bin(102, 100, 125_000), _bin(103, 100, 120_000, bad=1),
             _bin(104, 100, 130_000, mx=1100), _bin(105, 20, 10_000), _bin(106, 0, 0, mx=0),
             json.dumps({"summary": True, "first_unix": 101.5, "last_unix": 105.2, "stopped_by": "deadline"})]
    log.write_text("\n".join(lines) + "\n")
    s = video.read_sink_log(log)
    assert (s.datagrams, s.payload_bytes, s.not_rtp_h264, s.max_datagram_bytes) == (370, 425_000, 1, 1200)
    assert (s.first_unix, s.last_unix, s.stopped_by) == (101.5, 105.2, "deadline")
    assert s.active_s == pytest.approx(3.7) and s.rate_kbps == pytest.approx(425_000 * 8 / 3.7 / 1000)
    assert s.per_second_kbps()[2] == (102, 1000.0) and len(s.per_second_kbps()) == 7
    # whole bins in [102.5, 105.2]: 103 and 104
    assert s.steady_rate_kbps() == pytest.approx((120_000 + 130_000) * 8 / 2 / 1000)
    assert s.steady_rate_kbps(skip_s=0.5) == pytest.approx((125_000 + 120_000 + 130_000) * 8 / 3 / 1000)
    with pytest.raises(ValueError, match="no whole 1 s bin"):
        s.steady_rate_kbps(skip_s=3.0)
    # killed sink: no summary line, the non-empty bins' edges stand in
    log.write_text("\n".join(lines[:-1]) + "\n")
    k = video.read_sink_log(log)
    assert (k.first_unix, k.last_unix, k.stopped_by) == (101.0, 106.0, None)
    assert k.steady_rate_kbps() == pytest.approx((125_000 + 120_000 + 130_000 + 10_000) * 8 / 4 / 1000)
    log.write_text(_bin(100, 0, 0) + "\n")
    with pytest.raises(ValueError, match="received nothing"):
        video.read_sink_log(log).steady_rate_kbps()
    log.write_text(_bin(100, 1, 10) + "\n{\"t_unix\": 1}\n")
    with pytest.raises(ValueError, match=r"s.jsonl:2: not a sink log line"):
        video.read_sink_log(log)


def _start_sink(args: list[str]) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "uavcas.traffic.video", "sink", *args], env=_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_file(path: Path, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not path.exists():  # the sink opens its log right after binding
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.02)


def test_sink_counts_bins_and_stops_on_sigterm(tmp_path):
    port = _free_udp_pair()
    log = tmp_path / "k.jsonl"
    p = _start_sink(["--bind", "127.0.0.1", "--port", str(port), "--seconds", "30", "--log", str(log)])
    try:
        _wait_file(log)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            for _ in range(5):
                s.sendto(_rtp(), ("127.0.0.1", port))
            s.sendto(b"junk" * 100, ("127.0.0.1", port))
        time.sleep(1.2)  # at least one bin edge passes
        t0 = time.monotonic()
        p.send_signal(signal.SIGTERM)
        assert p.wait(5) == 0 and time.monotonic() - t0 < 1.0, p.stderr.read()
    finally:
        if p.poll() is None:
            p.kill()
    k = video.read_sink_log(log)
    assert (k.datagrams, k.not_rtp_h264, k.payload_bytes, k.max_datagram_bytes) == (6, 1, 5 * len(_rtp()) + 400, 400)
    assert k.stopped_by == "signal" and len(k.bins) >= 2
    assert [b.t_unix for b in k.bins] == list(range(k.bins[0].t_unix, k.bins[0].t_unix + len(k.bins)))


def test_sink_cli_errors_are_one_line(tmp_path):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as busy:
        busy.bind(("127.0.0.1", 0))
        port = busy.getsockname()[1]
        p = _start_sink(["--bind", "127.0.0.1", "--port", str(port), "--seconds", "2", "--log", str(tmp_path / "x")])
        out, err = p.communicate(timeout=20)
    assert p.returncode == 1 and err.strip().count("\n") == 0 and "in use" in err, err
    p = _start_sink(["--port", "5600", "--seconds", "-1", "--log", str(tmp_path / "x")])
    _, err = p.communicate(timeout=20)
    assert p.returncode == 2 and "--seconds -1.0 must be > 0" in err


def _nal_types(annexb: bytes) -> list[int]:
    out, i = [], annexb.find(b"\0\0\1")
    while i >= 0:
        out.append(annexb[i + 3] & 0x1F)
        i = annexb.find(b"\0\0\1", i + 3)
    return out


@needs_ffmpeg
def test_same_seed_same_encoded_frames(tmp_path):
    """Bit-exact: the x264 preset and one encoder/filter thread make the whole chain deterministic."""
    def encode(seed: int, name: str) -> bytes:
        spec = _spec(tmp_path, seed=seed, bitrate_kbps=800)
        subprocess.run(video.file_argv(spec, tmp_path / name, 2.0), check=True, timeout=60,
                       stdin=subprocess.DEVNULL, capture_output=True)
        return (tmp_path / name).read_bytes()

    a, b, c = encode(5, "a.h264"), encode(5, "b.h264"), encode(6, "c.h264")
    assert a == b and a != c
    types = _nal_types(a)
    assert types[:2] == [7, 8] and types.count(5) == 2  # SPS, PPS first; one IDR per 1 s GOP
    # CBR: 2 s at 800 kbit/s is 200 kB of H.264, give or take the SEI headers and the VBV
    assert 0.9 * 200_000 <= len(a) <= 1.1 * 200_000, len(a)


@needs_ffmpeg
@pytest.mark.slow
def test_stream_packets_are_rtp_h264(tmp_path):
    """Every datagram, received by the test itself: RTP v2, PT 96, the seeded SSRC, contiguous
    sequence numbers from the seeded first one, an H.264 unit, at most pkt_size bytes; no RTCP."""
    port = _free_udp_pair()
    spec = _spec(tmp_path, port=port, duration_s=3.0, bitrate_kbps=800, seed=3)
    rx, rtcp = (socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(2))
    rx.bind(("127.0.0.1", port))
    rtcp.bind(("127.0.0.1", port + 1))
    rx.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
    p = subprocess.Popen(video.sender_argv(spec), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE)
    got: list[bytes] = []
    try:
        rx.settimeout(5.0)  # ffmpeg start-up, then packets every few ms until it ends
        while True:
            try:
                got.append(rx.recv(65535))
            except socket.timeout:
                break
            rx.settimeout(1.0)
        assert p.wait(10) == 0, p.stderr.read()
        rtcp.setblocking(False)
        with pytest.raises(BlockingIOError):
            rtcp.recv(65535)
    finally:
        if p.poll() is None:
            p.kill()
        rx.close()
        rtcp.close()
    assert len(got) > 200
    seqs = [struct.unpack("!H", d[2:4])[0] for d in got]
    assert seqs[0] == spec.first_seq and all((b - a) % 65536 == 1 for a, b in zip(seqs, seqs[1:]))
    assert {struct.unpack("!I", d[8:12])[0] for d in got} == {spec.ssrc}
    assert all(d[0] >> 6 == 2 and d[1] & 0x7F == 96 and video.rtp_h264_ok(d) for d in got)
    assert max(len(d) for d in got) <= spec.pkt_size_bytes
    assert sum(len(d) == spec.pkt_size_bytes for d in got) > len(got) // 2  # frames fill whole packets
    assert {d[12] & 0x1F for d in got} >= {28}  # FU-A fragments carry the frames


@needs_ffmpeg
@pytest.mark.slow
def test_stream_rate_at_the_sink(tmp_path):
    """A 9 s stream at 800 kbit/s: the sink's steady rate (first second skipped) is within 10 %."""
    port = _free_udp_pair()
    spec = _spec(tmp_path, port=port, duration_s=9.0, bitrate_kbps=800, seed=21)
    argv = video.sink_argv(spec, python=sys.executable)
    sink = subprocess.Popen(argv, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_file(spec.log_path)
        send = subprocess.run(video.sender_argv(spec), stdin=subprocess.DEVNULL, capture_output=True,
                              text=True, timeout=spec.duration_s + 20)
        assert send.returncode == 0, send.stderr
        assert sink.wait(spec.duration_s + 20) == 0, sink.stderr.read()
    finally:
        if sink.poll() is None:
            sink.kill()
    s = video.read_sink_log(spec.log_path)
    steady = s.steady_rate_kbps(skip_s=1.0)
    print(f"steady {steady:.1f} kbit/s, whole stream {s.rate_kbps:.1f} kbit/s over {s.active_s:.2f} s, "
          f"{s.datagrams} datagrams, per second {[round(k) for _, k in s.per_second_kbps()]}")
    assert abs(steady - spec.bitrate_kbps) <= 0.1 * spec.bitrate_kbps, steady
    assert s.stopped_by == "deadline" and s.not_rtp_h264 == 0
    assert 0 < s.max_datagram_bytes <= spec.pkt_size_bytes
    assert spec.duration_s - 1.0 <= s.active_s <= spec.duration_s + 1.0


def test_video_seeds_repeat_per_plan_seed_and_differ_per_stream(tmp_path):
    p = plan("benign-4-2-video-logdist-adaptive-random-30-95", seed=7, windows=1)
    t = VideoApp(AppContext(None, p, tmp_path, 5.0))
    seeds = [t.spec("bs0", k).seed for k in range(4)]
    assert seeds == [VideoApp(AppContext(None, p, tmp_path, 5.0)).spec("bs0", k).seed for k in range(4)]
    assert len(set(seeds)) == 4
    other = VideoApp(AppContext(None, plan("benign-4-2-video-logdist-adaptive-random-30-95", seed=8, windows=1),
                                tmp_path, 5.0))
    assert seeds != [other.spec("bs0", k).seed for k in range(4)]


def test_the_runs_video_seeds_fit_ffmpeg_whatever_the_plan_seed(tmp_path):
    # campaign runs carry seeds up to 2**32 - 1; ffmpeg's noise seed is a C int
    p = plan("benign-4-2-video-logdist-adaptive-random-30-95", seed=2**32 - 1, windows=1)
    t = VideoApp(AppContext(None, p, tmp_path, 5.0))
    seeds = [t.spec("bs0", k).seed for k in range(4)]
    assert all(0 <= s <= video.MAX_SEED for s in seeds) and len(set(seeds)) == 4
    assert seeds == [VideoApp(AppContext(None, p, tmp_path, 5.0)).spec("bs0", k).seed for k in range(4)]
