"""What a traffic app is (`TrafficApp`) and what it gets to run on (`AppContext`, `AppOptions`).

A traffic app is one kind of benign traffic of a run: its server side is listening before t0
(`start_servers`), its client side starts at t0 (`start_clients`), and it reports what it did
(`streams`: its section of run.json's `streams`; `client_summaries`: its rows of run.json's
`http_clients`). A payload runs a list of apps (`payloads.PAYLOADS`); `benign.BenignTraffic`
drives them in that order, knowing none by name.

Every app serves the same pairs: UAV i talks to BS i mod n_bs (`AppContext.pairs`), so an
image client, a ground station and a video sink of a UAV sit on the same base station.
"""

from __future__ import annotations

import subprocess
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, ClassVar, Protocol

from uavcas.emulation.apps.procs import Proc
from uavcas.twin.model import Node, Plan

from . import mavlink, video
from .image import client, images

SERVER_READY_S = 15.0  # a server (nginx, a video sink) must listen within this after its start
# The MAVLink endpoints' and the video senders' own deadlines lie this far past the run's end, and
# `stop()` ends them right after it: when 8 Python endpoints and 6 ffmpeg exited exactly at the end,
# their exit landed on the last attack stop and delayed it by 90-160 ms (quick blackhole+dos run).
APP_OVERRUN_S = 3.0


class Hosts(Protocol):
    """What an app needs of a built emulation (`emulation.emulation.Emulation`): start a process in
    a node's namespace under `timeout`, and the namespace's name."""

    def popen(self, node: str, argv: Sequence[str], timeout_s: float | None = None, **kw) -> subprocess.Popen: ...

    def ns(self, node: str) -> str: ...


@dataclass(frozen=True)
class AppOptions:
    """The run options the apps read (`emulation.runner.RunOptions` fills them)."""

    think_mean_s: float = client.THINK_MEAN_S  # mean pause between a BS's image fetches
    n_images: int = images.DEFAULT_COUNT
    stream_rates: mavlink.StreamRates = field(default_factory=mavlink.StreamRates)
    video_kbps: int = video.BITRATE_KBPS  # H.264 bitrate of each UAV's video
    mavlink_signing: bool = False  # MAVLink 2 signing on both ends with the run's key (mavlink/signing.py)


@dataclass(frozen=True)
class AppContext:
    """One run's benign traffic: the emulation (None where only specs are built, e.g. in tests),
    the plan, the run's work directory (logs under `log_dir`), the run's length and the options."""

    emu: Hosts | None
    plan: Plan
    work_dir: Path
    duration_s: float
    options: AppOptions = AppOptions()

    @property
    def log_dir(self) -> Path:
        return self.work_dir / "logs"

    @property
    def uavs(self) -> list[Node]:
        return [n for n in self.plan.nodes if n.kind == "uav"]

    @property
    def bss(self) -> list[Node]:
        return [n for n in self.plan.nodes if n.kind == "bs"]

    @cached_property
    def pairs(self) -> list[tuple[str, str]]:
        """(bs, uav) pairs, UAV i served by BS i mod n_bs (names in plan order)."""
        return client.assignments([u.name for u in self.uavs], [b.name for b in self.bss])

    def starter(self, node: str) -> Callable[..., subprocess.Popen]:
        """`procs.spawn`'s start function for a process in `node`'s namespace."""
        if self.emu is None:
            raise RuntimeError("this traffic context has no emulation to start processes in")
        emu = self.emu
        return lambda argv, t, **kw: emu.popen(node, argv, t, **kw)


class TrafficApp(ABC):
    """One registered traffic app (`registry.register`), built per run on its context.

    name: the token a payload row names (lower-case letters, digits, '_').
    summary: one line for docs and listings.
    carries_mavlink: the app's datagrams are MAVLink (the payloads that attack MAVLink, and
        `--mavlink-signing`, need one such app).
    early / procs: the processes it started; `stop` signals every app's `early` (clients that
        would fail against a stopping server) and waits for them before any app's `procs`.
    """

    name: ClassVar[str]
    summary: ClassVar[str]
    carries_mavlink: ClassVar[bool] = False

    def __init__(self, ctx: AppContext) -> None:
        self.ctx = ctx
        self.early: list[Proc] = []
        self.procs: list[Proc] = []

    @abstractmethod
    def start_servers(self) -> None:
        """Before t0: start what must be listening when the clock starts; return once it is (else
        raise RuntimeError with one line saying which process and why)."""

    @abstractmethod
    def start_clients(self, t0_unix: float) -> None:
        """At t0: start the traffic itself."""

    def streams(self) -> dict[str, Any] | None:
        """This app's section of run.json `streams`, read from its own logs after the stop (None:
        it has none)."""
        return None

    def client_summaries(self) -> list[dict[str, Any]]:
        """This app's rows of run.json `http_clients` (none by default)."""
        return []
