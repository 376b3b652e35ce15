"""SIGKILL a run mid-way, `uavcas clean` it, check nothing is left; N times (issue #14).

    sudo .venv/bin/python benchmarks/kill_clean_cycles.py [--cycles 5] [--config ddos=1000-6-2-...]

Each cycle starts `uavcas run` (its own session), waits until it registered, kills it with
SIGKILL after a different delay each time (setup, traffic, attack start, mid-attack...), runs
`uavcas clean --prefix P` and checks: clean exited 0, no namespace of the prefix, no registry
entry, no process naming the prefix (tools, `timeout` wrappers, flood pacers, the delay
daemon) after a short grace, and `uavcas extract` of the killed run exits non-zero.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from uavcas.testing import runcheck as rc

UAVCAS = str(Path(sys.executable).parent / "uavcas")


def leftovers(prefix: str) -> list[str]:
    ns = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout.split()
    out = [f"namespace {n}" for n in ns if n.startswith(prefix + "-")]
    if Path(f"/run/uavcas/{prefix}").exists():
        out.append(f"/run/uavcas/{prefix}")
    ps = subprocess.run(["ps", "-eo", "pid,args"], capture_output=True, text=True).stdout.splitlines()
    out += [f"process {ln.strip()[:120]}" for ln in ps if f"{prefix}-" in ln or f"/run/uavcas/{prefix}/" in ln]
    return out


def cycle(config: str, kill_after_s: float, work: Path) -> dict:
    out = work / f"run-{kill_after_s:g}"
    t = time.time()
    proc = subprocess.Popen([UAVCAS, "run", config, "--windows", "3", "--out", str(out)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    prefix = rc.wait_registered(proc.pid, t)
    time.sleep(kill_after_s)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(10)
    t_clean = time.monotonic()
    r = subprocess.run([UAVCAS, "clean", "--prefix", prefix], capture_output=True, text=True, timeout=120)
    clean_s = time.monotonic() - t_clean
    time.sleep(2.0)  # orphaned `timeout` wrappers and pacers exit once their tools/runner are gone
    left = leftovers(prefix)
    ex = subprocess.run([UAVCAS, "extract", str(out), "--out", str(work / "ds")], capture_output=True, text=True,
                        timeout=300)
    return {"prefix": prefix, "kill_after_s": kill_after_s, "clean_rc": r.returncode, "clean_s": round(clean_s, 2),
            "clean_said": (r.stdout + r.stderr).strip().splitlines()[-1:], "left": left,
            "extract_rc": ex.returncode, "extract_said": ex.stderr.strip()[:160]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=5)
    ap.add_argument("--config", default="replay=50,200,10,5,inc+ddos=1000-6-2-image-logdist-adaptive-random-30-95")
    a = ap.parse_args()
    delays = [0.5 + 1.7 * k for k in range(a.cycles)]  # setup ... late in the run
    with tempfile.TemporaryDirectory(prefix="uavcas-kill-") as tmp:
        rows = [cycle(a.config, d, Path(tmp)) for d in delays]
    for r in rows:
        print(json.dumps(r))
    bad = [r for r in rows if r["clean_rc"] != 0 or r["left"] or r["extract_rc"] == 0]
    print(f"{len(rows) - len(bad)}/{len(rows)} cycles left nothing behind and refused extraction")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
