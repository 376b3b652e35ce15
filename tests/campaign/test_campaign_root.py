"""Real campaigns on the emulator (root): resume after a kill (on Dask: test_campaign_dask.py)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pyarrow.parquet as pq
import pytest

from helpers.campaign_runs import cli, write_manifest

pytestmark = [pytest.mark.root, pytest.mark.slow]


def test_killed_campaign_resumes_without_duplicates(tmp_path):
    m = tmp_path / "m.jsonl"
    write_manifest(m)
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
    r = cli("campaign", "run", "--manifest", str(m), "--out", str(ds), timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    for i, data in before.items():  # finished runs are not redone
        assert (ds / "shards" / f"{i}.parquet").read_bytes() == data
    union = pq.read_table(ds / "flows.parquet")
    shards = [pq.read_table(ds / "shards" / f"{i}.parquet") for i in range(3)]
    assert union.num_rows == sum(s.num_rows for s in shards)  # every run exactly once
    assert sorted(set(union.column("run_id").to_pylist())) == [str(i) for i in range(3)]
    assert "already done" in r.stdout

