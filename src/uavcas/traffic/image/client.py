"""The base stations' HTTP clients: BS `i mod n_bs` fetches UAV i's images continuously.

One bash loop per UAV runs in its BS's namespace: curl an image (a seeded sequence over the
image set), log one line, think for a seeded pause, repeat until the time budget is spent.
A new TCP connection per image, as a ground station pulling frames would, so every fetch is
its own flow. Bounded three ways: the loop's own deadline (bash `SECONDS`), curl's
`--max-time`, and the `timeout` the core wraps around the whole script.

While the plan marks the UAV disconnected (no usable path to any BS, `Route.disconnected`) the
loop fetches nothing: it logs one `skip` line and sleeps to the end of that window, so no benign
traffic is sent into the void (it would vanish exactly as a blackhole's does). Windows are
counted from the run's t0 (`ClientSpec.t0_unix`), with bash's microsecond clock.

Log line (tab separated): epoch start, HTTP code (000 = no answer), bytes, seconds, the client's
TCP port (curl's `local_port`: it names the connection in the captures; 0 when the connect failed),
image; or epoch, `skip`, 0, 0, the window index for a window skipped while disconnected. Logs
written before the port was logged (five fields) still parse.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from uavcas import seeding

THINK_MEAN_S = 0.5  # mean pause between fetches: ~1.5 images/s per UAV, a few Mbit/s in total
CONNECT_TIMEOUT_S = 2.0
MAX_TIME_S = 8.0
SEQUENCE_LEN = 256  # cycled; long enough that the order does not visibly repeat in a run


@dataclass(frozen=True)
class ClientSpec:
    bs: str
    uav: str
    uav_ip: str
    images: tuple[str, ...]
    duration_s: float
    log_path: Path
    seed: int  # the plan's seed; the client draws from its stream ("http-client", index)
    index: int = 0  # the client's position in `assignments` (one stream per client)
    think_mean_s: float = THINK_MEAN_S
    port: int = 80
    t0_unix: float = 0.0  # plan t = 0 (the windows below count from it)
    window_s: float = 5.0
    offline_windows: tuple[int, ...] = ()  # windows in which the UAV reaches no BS


@dataclass(frozen=True)
class Fetch:
    t_unix: float
    code: int
    size_bytes: int
    seconds: float
    image: str
    local_port: int | None = None  # None: a log from before the port was recorded

    @property
    def ok(self) -> bool:
        return 200 <= self.code < 300


def assignments(uavs: list[str], bss: list[str]) -> list[tuple[str, str]]:
    """(bs, uav) pairs: UAV i is served by BS i mod n_bs (names in plan order)."""
    if not bss:
        return []
    return [(bss[i % len(bss)], u) for i, u in enumerate(uavs)]


def draw_sequence(spec: ClientSpec) -> tuple[list[str], np.ndarray]:
    """The script's image order and think times (s), from the client's own stream of the plan's seed."""
    rng = seeding.generator(spec.seed, "http-client", spec.index)
    order = [spec.images[int(k)] for k in rng.integers(0, len(spec.images), SEQUENCE_LEN)]
    # Exponential think times, clipped: a bursty but bounded request process.
    thinks = np.clip(rng.exponential(spec.think_mean_s, SEQUENCE_LEN), 0.05, 4 * spec.think_mean_s)
    return order, thinks


def render_script(spec: ClientSpec) -> str:
    order, thinks = draw_sequence(spec)
    url = f"http://{spec.uav_ip}:{spec.port}/"
    fmt = r"%{http_code}\t%{size_download}\t%{time_total}\t%{local_port}"
    offline = ""
    if spec.offline_windows:
        # ${EPOCHREALTIME/./}: the epoch in microseconds (bash 5 prints 6 decimals)
        offline = """  now=${t/./}
  w=$(( (now - t0us) / wus ))
  if [[ "$off" == *" $w "* ]]; then
    printf '%s\\tskip\\t0\\t0\\t%s\\n' "$t" "$w" >> "$log"
    rest=$(( t0us + (w + 1) * wus - now ))
    sleep "$(( rest / 1000000 )).$(printf '%06d' $(( rest % 1000000 )))"
    continue
  fi
"""
    return f"""#!/bin/bash
# uavcas: {spec.bs} fetching images from {spec.uav} (generated)
imgs=({' '.join(shlex.quote(i) for i in order)})
thinks=({' '.join(f'{t:.3f}' for t in thinks)})
log={shlex.quote(str(spec.log_path))}
t0us={round(spec.t0_unix * 1e6)}
wus={round(spec.window_s * 1e6)}
off=" {' '.join(str(w) for w in spec.offline_windows)} "
end=$((SECONDS + {int(np.ceil(spec.duration_s))}))
i=0
while (( SECONDS < end )); do
  t=$EPOCHREALTIME
{offline}  img=${{imgs[i % {SEQUENCE_LEN}]}}
  r=$(curl -s -o /dev/null --connect-timeout {CONNECT_TIMEOUT_S:g} --max-time {MAX_TIME_S:g} -w '{fmt}' "{url}$img")
  printf '%s\\t%s\\t%s\\n' "$t" "$r" "$img" >> "$log"
  sleep "${{thinks[i % {SEQUENCE_LEN}]}}"
  i=$((i + 1))
done
"""


def write_script(spec: ClientSpec, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(render_script(spec))
    path.chmod(0o755)
    return path


def parse_log(text: str) -> list[Fetch]:
    """The fetches of a client log (skipped windows are not fetches: see `skipped_windows`)."""
    out = []
    for line in text.splitlines():
        parts = line.split("\t")
        if len(parts) not in (5, 6) or parts[1] == "skip":
            continue
        try:
            port = int(parts[4]) if len(parts) == 6 else None
            out.append(Fetch(float(parts[0]), int(parts[1]), int(float(parts[2])), float(parts[3]), parts[-1], port))
        except ValueError:
            continue
    return out


def skipped_windows(text: str) -> list[int]:
    """Windows the client skipped because its UAV was disconnected, in log order."""
    out = []
    for line in text.splitlines():
        parts = line.split("\t")
        if len(parts) == 5 and parts[1] == "skip" and parts[4].isdigit():
            out.append(int(parts[4]))
    return out
