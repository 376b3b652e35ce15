"""The throwaway traffic app and payload row of the traffic drop-in tests
(tests/traffic/test_traffic_dropin.py, and its real run in test_traffic_dropin_root.py)."""

from __future__ import annotations

from pathlib import Path

from helpers.plugin import package_copy

THROWAWAY = '''"""Throwaway app for a test: TCP echo, a server per BS and a client per UAV."""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any, ClassVar

from uavcas.emulation.apps.procs import spawn, wait_for

from ..base import APP_OVERRUN_S, SERVER_READY_S, TrafficApp
from ..registry import register

PORT = 7007
BLOCK_BYTES = 512
SERVER = r"""
import signal, socket, sys, time
host, port, until, log = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
signal.signal(signal.SIGTERM, lambda *a: sys.exit(0))
s = socket.create_server((host, port))
s.settimeout(0.2)
print("ready", flush=True)
n = 0
while time.time() < until:
    try:
        c, _ = s.accept()
    except TimeoutError:
        continue
    with c:
        c.settimeout(1.0)
        data = c.recv(65536)
        c.sendall(data)
    n += 1
    open(log, "w").write(str(n))
"""
CLIENT = r"""
import signal, socket, sys, time
host, port, until, size = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
signal.signal(signal.SIGTERM, lambda *a: sys.exit(0))
while time.time() < until:
    try:
        with socket.create_connection((host, port), timeout=1.0) as c:
            c.sendall(b"e" * size)
            c.recv(65536)
    except OSError:
        pass
    time.sleep(0.2)
"""


@register
class EchoApp(TrafficApp):
    name: ClassVar[str] = "echo"
    summary: ClassVar[str] = "TCP echo: a server per BS, a client per UAV"

    def _log(self, bs: str) -> Path:
        return self.ctx.log_dir / f"echo-{bs}.txt"

    def start_servers(self) -> None:
        ctx = self.ctx
        until = str(time.time() + ctx.duration_s + 60 + APP_OVERRUN_S)
        for b in ctx.bss:
            argv = [sys.executable, "-c", SERVER, b.ip, str(PORT), until, str(self._log(b.name))]
            self.procs.append(spawn(ctx.starter(b.name), f"echo-{b.name}", argv, ctx.log_dir, ctx.duration_s + 90))
        if not wait_for(lambda: all(p.stdout().startswith("ready") for p in self.procs), SERVER_READY_S, 0.05):
            raise RuntimeError("echo server did not start")

    def start_clients(self, t0_unix: float) -> None:
        ctx = self.ctx
        until = str(t0_unix + ctx.duration_s)
        for bs, uav in ctx.pairs:
            argv = [sys.executable, "-c", CLIENT, ctx.plan.node(bs).ip, str(PORT), until, str(BLOCK_BYTES)]
            self.early.append(spawn(ctx.starter(uav), f"echo-{uav}", argv, ctx.log_dir, ctx.duration_s + 30))

    def streams(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for b in self.ctx.bss:
            path = self._log(b.name)
            out[b.name] = {"echoed": int(path.read_text() or 0) if path.exists() else 0}
        return out
'''
ROW = '    "echo": ("echo",),\n'
CONFIG = "benign-2-1-echo-logdist-adaptive-random-30-95"


def copy_with_throwaway(tmp: Path) -> Path:
    dst = package_copy(tmp, {"traffic/apps/echo.py": THROWAWAY})
    table = dst / "uavcas" / "traffic" / "payloads.py"
    text = table.read_text()
    anchor = '    "mixed": ("mavlink", "video", "image"),\n'
    assert text.count(anchor) == 1  # the row goes after the table's last one
    table.write_text(text.replace(anchor, anchor + ROW))
    return dst
