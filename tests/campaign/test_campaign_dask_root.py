"""Campaigns on a real Dask cluster (root): a scheduler and `dask worker` processes started apart.

Four runs over two workers land once each; a worker killed (SIGKILL to its process group) while
it emulates has its run retried on the other worker, and nothing of the killed try's namespaces
stays; workers without `--resources emulator=1` are refused in one line within 30 s; the Dask
dataset is a local campaign's but for real-time jitter. Runs are real time, so two executions of
one scenario never give bit-identical packets: what must be identical is everything the plan
decides (plan.json bytes, the config/seed columns, the schema, and per run the set of (src_ip,
dst_ip, dst_port, protocol, label) services); timing columns, ephemeral ports and packet counts
move with real-time jitter.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pyarrow.parquet as pq
import pytest

import uavcas
from helpers.campaign_runs import cli, free_port, services, write_manifest
from helpers.root_campaigns import WINDOW_S
from uavcas.emulation import kernel
from uavcas.network.naming import RUN_ROOT

pytestmark = [pytest.mark.root, pytest.mark.slow]

DASK = Path(sys.executable).parent / "dask"
# the scheduler unpickles the task graph and the workers run it: both import this tree's uavcas
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(uavcas.__file__).resolve().parents[1]),
                                                    os.environ.get("PYTHONPATH", "")])}


@dataclass
class Cluster:
    address: str
    workers: list[subprocess.Popen]  # each the leader of its own process group


@contextmanager
def cluster(tmp_path: Path, n_workers: int = 2, emulator: bool = True) -> Iterator[Cluster]:
    """A scheduler and `n_workers` workers (`--nthreads 1`, with or without `--resources emulator=1`)."""
    if not DASK.exists():
        pytest.skip(f"dask CLI not installed next to {sys.executable}")
    address = f"tcp://127.0.0.1:{free_port()}"
    procs = []

    def start(args: list[str], log: str) -> subprocess.Popen:
        with open(tmp_path / log, "w") as fh:
            procs.append(subprocess.Popen([str(DASK), *args], stdout=fh, stderr=subprocess.STDOUT, env=ENV,
                                          start_new_session=True))
        return procs[-1]

    try:
        start(["scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1], "--no-dashboard"],
              "scheduler.log")
        resources = ["--resources", "emulator=1"] if emulator else []
        workers = [start(["worker", address, "--nthreads", "1", *resources, "--no-dashboard",
                          "--local-directory", str(tmp_path / f"w{i}")], f"worker{i}.log") for i in range(n_workers)]
        yield Cluster(address, workers)
    finally:
        for p in procs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def _started(output: str) -> list[int]:
    """The runs the campaign saw start on a worker, once per start (not the moves of a retry)."""
    return sorted(int(i) for i in re.findall(r"^run (\d+) started on worker", output, re.M))


def _assert_each_once(ds: Path, n: int) -> None:
    assert all((ds / "runs" / str(i) / "DONE").is_file() for i in range(n))
    union = pq.read_table(ds / "flows.parquet", columns=["run_id"])
    shards = [pq.read_table(ds / "shards" / f"{i}.parquet", columns=["run_id"]) for i in range(n)]
    assert union.num_rows == sum(s.num_rows for s in shards)  # each run's rows exactly once
    assert sorted(set(union.column("run_id").to_pylist())) == [str(i) for i in range(n)]
    assert json.loads((ds / "dataset.json").read_text())["n_runs"] == n


@dataclass(frozen=True)
class DaskCampaign:
    ds: Path
    result: subprocess.CompletedProcess


@pytest.fixture(scope="module")
def four_runs(tmp_path_factory) -> DaskCampaign:
    """Four runs over two workers: checked by the first test, compared with local runs by the last."""
    tmp = tmp_path_factory.mktemp("dask4")
    m = tmp / "m.jsonl"
    write_manifest(m, n=4, window_s=WINDOW_S)
    with cluster(tmp) as c:
        r = cli("campaign", "run", "--manifest", str(m), "--out", str(tmp / "ds"), "--scheduler", c.address,
                "--no-report", timeout=300)
    return DaskCampaign(tmp / "ds", r)


def test_four_runs_over_two_workers_land_once_each(four_runs):
    r = four_runs.result
    out = r.stdout + r.stderr
    assert r.returncode == 0, out[-3000:]
    assert _started(out) == [0, 1, 2, 3], out[-3000:]  # progress names each start, and each ran once
    assert "retrying" not in out and "moved to" not in out
    _assert_each_once(four_runs.ds, 4)


def _run_child(workers: list[subprocess.Popen]) -> tuple[int, subprocess.Popen] | None:
    """A run's child (`python -m uavcas.campaign.worker`) whose parent is in a worker's group."""
    groups = {w.pid: w for w in workers}
    for d in Path("/proc").iterdir():
        try:
            if not d.name.isdigit() or b"uavcas.campaign.worker" not in (d / "cmdline").read_bytes():
                continue
            ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            if os.getpgid(ppid) in groups:
                return int(d.name), groups[os.getpgid(ppid)]
        except (OSError, ValueError):  # gone meanwhile
            continue
    return None


def _prefix_of(pid: int) -> str | None:
    """The namespace prefix of the run `pid` emulates, once its namespaces exist."""
    for rec in RUN_ROOT.glob("*/run.json"):
        try:
            data = json.loads(rec.read_text())
        except (OSError, ValueError):
            continue
        if data["pid"] == pid and set(data["namespaces"]) <= set(kernel.netns_list()):
            return data["prefix"]
    return None


def test_a_worker_killed_mid_run_has_its_run_retried_and_leaves_no_namespace(tmp_path):
    m = tmp_path / "m.jsonl"
    write_manifest(m, n=4, window_s=WINDOW_S)
    log = tmp_path / "campaign.log"
    with cluster(tmp_path) as c, open(log, "w") as fh:
        proc = subprocess.Popen([sys.executable, "-m", "uavcas.cli", "campaign", "run", "--manifest", str(m), "--out",
                                 str(tmp_path / "ds"), "--scheduler", c.address, "--no-report"],
                                stdout=fh, stderr=subprocess.STDOUT)
        try:
            victim = prefix = None
            deadline = time.monotonic() + 120
            while prefix is None and time.monotonic() < deadline and proc.poll() is None:
                time.sleep(0.1)
                victim = _run_child(c.workers)
                prefix = _prefix_of(victim[0]) if victim else None
            assert victim and prefix, "no run was emulating on a worker"
            child, worker = victim
            os.killpg(worker.pid, signal.SIGKILL)  # the worker and its nanny, at once, mid-run
            worker.wait()
            rc = proc.wait(timeout=300)
        finally:
            if proc.poll() is None:
                proc.kill()
    out = log.read_text()
    assert rc == 0, out[-3000:]
    _assert_each_once(tmp_path / "ds", 4)
    killed = re.findall(r"^run (\d+) moved to worker", out, re.M)
    assert len(killed) == 1, out[-3000:]  # the killed try went to the other worker, by Dask's retry
    deadline = time.monotonic() + 60  # the child's teardown (SIGTERM on its parent's death) may lag
    while time.monotonic() < deadline and (Path(f"/proc/{child}").exists() or
                                           any(ns.startswith(f"{prefix}-") for ns in kernel.netns_list())):
        time.sleep(0.5)
    assert not [ns for ns in kernel.netns_list() if ns.startswith(f"{prefix}-")]
    assert not (RUN_ROOT / prefix).exists()


def test_workers_without_the_emulator_resource_are_refused_in_one_line(tmp_path):
    m = tmp_path / "m.jsonl"
    write_manifest(m, n=1, window_s=WINDOW_S)
    with cluster(tmp_path, emulator=False) as c:
        time.sleep(5)  # the workers have joined: refused for lacking the resource, not for absence
        t0 = time.monotonic()
        r = cli("campaign", "run", "--manifest", str(m), "--out", str(tmp_path / "ds"), "--scheduler", c.address,
                timeout=60)
        waited = time.monotonic() - t0
    out = r.stdout + r.stderr
    assert r.returncode != 0 and waited < 30, (waited, out[-2000:])  # the bound, start-up included
    lines = [ln for ln in out.splitlines() if "--resources emulator=1" in ln]
    assert len(lines) == 1 and "2 worker(s) without it" in lines[0], out[-2000:]
    assert not (tmp_path / "ds" / "runs").exists() or not any((tmp_path / "ds" / "runs").iterdir())


def test_dask_cluster_gives_the_same_runs_plans_and_services_as_local(four_runs, resumed_campaign):
    # the local campaign is the session's resumed one (helpers.root_campaigns): its first two
    # manifest entries are the Dask campaign's first two (same configs, seeds and windows)
    assert four_runs.result.returncode == 0 and resumed_campaign.resume.returncode == 0
    dask_ds, local_ds = four_runs.ds, resumed_campaign.ds
    for e in resumed_campaign.entries[:2]:
        a = (dask_ds / "runs" / str(e.index) / "plan.json").read_bytes()
        b = (local_ds / "runs" / str(e.index) / "plan.json").read_bytes()
        assert a == b
    td, tl = pq.read_table(dask_ds / "flows.parquet"), pq.read_table(local_ds / "flows.parquet")
    assert td.schema.remove_metadata() == tl.schema.remove_metadata()
    key = ["run_id", "config", "seed"]

    def runs(t) -> set:
        return {r for r in map(tuple, t.select(key).to_pandas().to_numpy().tolist()) if r[0] in ("0", "1")}

    assert runs(td) == runs(tl) and len(runs(td)) == 2
    sd, sl = services(dask_ds), services(local_ds)
    assert {"0", "1"} <= sd.keys() and {"0", "1"} <= sl.keys()
    for k in ("0", "1"):
        # the services (who talks to whom on which port, and how it is labeled) match; a flood's
        # SYNs each open a new source port, which is why ports of the initiator are left out
        assert sd[k] == sl[k], (k, sd[k] ^ sl[k])
