"""A traffic app is added by dropping one module into `uavcas.traffic.apps`, and a payload by one
row of `uavcas.traffic.payloads.PAYLOADS` (issue 40).

A copy of the package gets a throwaway app, `echo`: a TCP echo server on every base station and
a client per UAV that sends a block to its BS and reads it back, over and over; and a payload
`echo` whose row names it. In a fresh interpreter that imports only the copy, the registry offers
the app, the scenario codec accepts the payload (and still refuses one the table lacks, in one
line), `uavcas plan` plans it, and `uavcas run --mavlink-signing` refuses it for carrying no
MAVLink, before any root check. The real run of the payload (root) checks that its run.json
carries the app's own section, with blocks echoed on every BS.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import uavcas

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


def _copy_with_throwaway(tmp: Path) -> Path:
    src = Path(uavcas.__file__).parent
    dst = tmp / "pkg"
    shutil.copytree(src, dst / "uavcas", ignore=shutil.ignore_patterns("__pycache__"))
    (dst / "uavcas" / "traffic" / "apps" / "echo.py").write_text(THROWAWAY)
    table = dst / "uavcas" / "traffic" / "payloads.py"
    text = table.read_text()
    anchor = '    "mixed": ("mavlink", "video", "image"),\n'
    assert text.count(anchor) == 1  # the row goes after the table's last one
    table.write_text(text.replace(anchor, anchor + ROW))
    return dst


def _run(pkg: Path, *args: str, timeout_s: float = 600) -> subprocess.CompletedProcess:
    # PYTHONPATH puts the copy before the editable install of the work tree
    env = {**os.environ, "PYTHONPATH": str(pkg), "COLUMNS": "200", "NO_COLOR": "1", "TERM": "dumb"}
    return subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True, timeout=timeout_s)


def test_a_dropped_in_app_and_payload_row_are_registered_parsed_and_planned(tmp_path):
    pkg = _copy_with_throwaway(tmp_path)
    probe = _run(pkg, "-c", "import uavcas, uavcas.traffic.apps as a; from uavcas.scenario import parse; "
                            "print(uavcas.__file__); print(' '.join(a.names())); print(' '.join(a.MAVLINK_PAYLOADS)); "
                            "print([c.__name__ for c in a.payload_apps('echo')]); "
                            f"print(parse({CONFIG!r}).payload)")
    assert probe.returncode == 0, probe.stderr
    where, names, mavlink, classes, payload = probe.stdout.splitlines()
    assert where.startswith(str(pkg))
    assert names.split() == ["echo", "image", "mavlink", "video"]  # module order
    assert mavlink.split() == ["telemetry", "video", "mixed"]  # echo carries no MAVLink
    assert classes == "['EchoApp']" and payload == "echo"

    refused = _run(pkg, "-m", "uavcas", "plan", CONFIG.replace("echo", "ping"))
    assert refused.returncode != 0
    assert "field 'payload': 'ping' is not one of image, telemetry, video, mixed, echo" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1, refused.stderr

    out = tmp_path / "plan.json"
    planned = _run(pkg, "-m", "uavcas", "plan", CONFIG, "--seed", "3", "--windows", "1", "--out", str(out))
    assert planned.returncode == 0, planned.stderr
    plan = json.loads(out.read_text())
    assert plan["config"] == CONFIG and plan["scenario"]["payload"] == "echo"
    assert sum(n["kind"] == "uav" for n in plan["nodes"]) == 2 and len(plan["windows"]) == 1

    signed = _run(pkg, "-m", "uavcas", "run", CONFIG, "--out", str(tmp_path / "run"), "--mavlink-signing")
    assert signed.returncode != 0 and "payload 'echo' carries no MAVLink" in signed.stderr
    assert not (tmp_path / "run").exists()


@pytest.mark.root
@pytest.mark.slow
def test_a_dropped_in_payload_runs_with_its_app(tmp_path):
    """One window, two UAVs, the echo payload emulated for real: the app's section in run.json."""
    pkg = _copy_with_throwaway(tmp_path)
    out = tmp_path / "run"
    ran = _run(pkg, "-m", "uavcas", "run", CONFIG, "--seed", "3", "--windows", "1", "--out", str(out),
               "--no-audit", timeout_s=300)
    assert ran.returncode == 0, ran.stderr[-2000:]
    info = json.loads((out / "run.json").read_text())
    assert info["http_clients"] == []  # no image app in this payload
    assert set(info["streams"]) == {"echo"}
    assert info["streams"]["echo"]["bs0"]["echoed"] > 0, info["streams"]
