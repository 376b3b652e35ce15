"""A supervised tool process: own session, stopped by PID with a chosen signal, output kept.

Every tool is started through the emulation core (`Emulation.popen` / `popen_fabric`), which
wraps it in `timeout` and registers its PID for teardown. We add two things the apps need:
* `start_new_session=True`, so a terminal Ctrl-C reaches only the runner, which then stops the
  tools in order (tcpdump must get SIGINT to flush and print its drop counters);
* stdout/stderr go to files (never pipes a chatty tool could fill and block on).
GNU `timeout` forwards the signal it receives to the tool, so signalling the Popen is enough.
"""

from __future__ import annotations

import signal
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class Proc:
    name: str
    popen: subprocess.Popen
    out_path: Path
    err_path: Path
    started_unix: float = field(default_factory=time.time)

    @property
    def pid(self) -> int:
        return self.popen.pid

    def alive(self) -> bool:
        return self.popen.poll() is None

    def stop(self, sig: int = signal.SIGTERM, grace_s: float = 3.0) -> int | None:
        """Send `sig`; SIGKILL after `grace_s`. Returns the exit code (None if it would not die)."""
        if self.popen.poll() is None:
            try:
                self.popen.send_signal(sig)
            except ProcessLookupError:
                pass
            try:
                self.popen.wait(grace_s)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                try:
                    self.popen.wait(2.0)
                except subprocess.TimeoutExpired:
                    return None
        return self.popen.returncode

    def stdout(self) -> str:
        return _read(self.out_path)

    def stderr(self) -> str:
        return _read(self.err_path)


def _read(path: Path) -> str:
    try:
        return path.read_text(errors="replace")
    except FileNotFoundError:
        return ""


def spawn(start, name: str, argv: list[str], log_dir: Path, timeout_s: float, **kw) -> Proc:
    """`start(argv, timeout_s, **kw)` is Emulation.popen bound to a node, or popen_fabric."""
    log_dir.mkdir(parents=True, exist_ok=True)
    out_path, err_path = log_dir / f"{name}.out", log_dir / f"{name}.err"
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        p = start(argv, timeout_s, stdout=out, stderr=err, stdin=subprocess.DEVNULL,
                  start_new_session=True, **kw)
    return Proc(name, p, out_path, err_path)


def wait_for(predicate, timeout_s: float, interval_s: float = 0.02) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(interval_s)
    return predicate()
