"""Real campaigns on the emulator (root): resume after a kill, and the same manifest on Dask.

Runs are real time, so two executions of one scenario never give bit-identical packets. What
must be identical is everything the plan decides: plan.json bytes, and per run the set of
(src_ip, dst_ip, dst_port, protocol, label) services; only timing columns, ephemeral ports and
packet counts may move with real-time jitter.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from uavcas.scenario import ManifestEntry

pytestmark = [pytest.mark.root, pytest.mark.slow]

TINY = (
    "benign-3-1-image-logdist-adaptive-random-30-95",
    "dos=1000-3-1-image-logdist-adaptive-spiral-30-95",
    "blackhole-3-1-image-logdist-adaptive-grid-30-95",
)


def _manifest(path: Path, window_s: float = 4.0) -> list[ManifestEntry]:
    entries = [
        ManifestEntry(index=i, position=i, config=c, seed=100 + i, windows=2, window_s=window_s)
        for i, c in enumerate(TINY)
    ]
    path.write_text("".join(json.dumps(e.to_dict()) + "\n" for e in entries))
    return entries


def _cli(*args: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "uavcas.cli", *args], capture_output=True, text=True, **kw)


def _services(ds: Path) -> dict[str, set]:
    cols = ["run_id", "src_ip", "dst_ip", "dst_port", "protocol", "label", "seq_flags"]
    t = pq.read_table(ds / "flows.parquet", columns=cols).to_pandas()
    # connections as opened (a TCP flow starting with a SYN, or any other protocol): the pieces a
    # FIN/RST cuts off (flows.assemble rule 4a) depend on retransmission timing, not on the service
    opening = [p != 6 or (len(f) > 0 and (int(f[0]) & 0x12) == 0x02) for p, f in zip(t.protocol, t.seq_flags)]
    t = t[opening]
    return {rid: set(map(tuple, g[["src_ip", "dst_ip", "dst_port", "protocol", "label"]].to_numpy().tolist()))
            for rid, g in t.groupby("run_id")}


def test_killed_campaign_resumes_without_duplicates(tmp_path):
    m = tmp_path / "m.jsonl"
    _manifest(m)
    ds = tmp_path / "ds"
    proc = subprocess.Popen([sys.executable, "-m", "uavcas.cli", "campaign", "run", "--manifest", str(m), "--out",
                             str(ds)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if any((ds / "runs").glob("*/DONE")):
            break
        time.sleep(0.2)
    first_done = sorted(p.parent.name for p in (ds / "runs").glob("*/DONE"))
    assert first_done, "no run finished before the kill"
    os.killpg(proc.pid, signal.SIGKILL)  # the whole campaign, emulation included, dies at once
    proc.wait()
    before = {i: (ds / "shards" / f"{i}.parquet").read_bytes() for i in first_done}
    subprocess.run([sys.executable, "-m", "uavcas.cli", "clean"], capture_output=True, timeout=60)
    r = _cli("campaign", "run", "--manifest", str(m), "--out", str(ds), timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    for i, data in before.items():  # finished runs are not redone
        assert (ds / "shards" / f"{i}.parquet").read_bytes() == data
    union = pq.read_table(ds / "flows.parquet")
    shards = [pq.read_table(ds / "shards" / f"{i}.parquet") for i in range(len(TINY))]
    assert union.num_rows == sum(s.num_rows for s in shards)  # every run exactly once
    assert sorted(set(union.column("run_id").to_pylist())) == [str(i) for i in range(len(TINY))]
    assert "already done" in r.stdout


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_dask_cluster_gives_the_same_plans_and_services_as_local(tmp_path):
    dask = shutil.which("dask", path=str(Path(sys.executable).parent)) or shutil.which("dask")
    if dask is None:
        pytest.skip("dask CLI not installed")
    m = tmp_path / "m.jsonl"
    entries = _manifest(m, window_s=3.0)[:2]
    m.write_text("".join(json.dumps(e.to_dict()) + "\n" for e in entries))
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    sched = subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True, env=env)
    worker = subprocess.Popen([dask, "worker", addr, "--nthreads", "1", "--nworkers", "1", "--resources", "emulator=1",
                               "--no-dashboard", "--local-directory", str(tmp_path / "w")],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True, env=env)
    try:
        r = _cli("campaign", "run", "--manifest", str(m), "--out", str(tmp_path / "dask"), "--scheduler", addr,
                 timeout=300)
        assert r.returncode == 0, r.stderr[-2000:]
        r = _cli("campaign", "run", "--manifest", str(m), "--out", str(tmp_path / "local"), timeout=300)
        assert r.returncode == 0, r.stderr[-2000:]
    finally:
        for p in (worker, sched):
            os.killpg(p.pid, signal.SIGTERM)
        for p in (worker, sched):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
    for e in entries:
        a = (tmp_path / "dask" / "runs" / str(e.index) / "plan.json").read_bytes()
        b = (tmp_path / "local" / "runs" / str(e.index) / "plan.json").read_bytes()
        assert a == b
    sd, sl = _services(tmp_path / "dask"), _services(tmp_path / "local")
    assert sd.keys() == sl.keys() == {"0", "1"}
    for k in sd:
        # the services (who talks to whom on which port, and how it is labeled) match; a flood's
        # SYNs each open a new source port, which is why ports of the initiator are left out
        assert sd[k] == sl[k], (k, sd[k] ^ sl[k])
