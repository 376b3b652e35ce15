"""Real campaigns shared by the root tests that read them (a pytest plugin: `tests/conftest.py`).

One emulated campaign costs minutes of real time, so a campaign is run once per session and
every test that only reads it shares it (issue 40: the full suite in 15 minutes on 2 cores):
- `resumed_campaign`: the TINY manifest's first 3 runs, killed (the whole process group, at
  once) after its first run is done, then resumed. `test_campaign_root` checks the resume,
  `test_publish_campaign_root` publishes its dataset, and `test_campaign_dask_root` compares a
  Dask cluster's runs with its first two (the same manifest entries, so the same plans).
A fixture requested by no selected test never runs: the fast tier pays nothing for these.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from helpers.campaign_runs import cli, write_manifest
from uavcas.scenario import ManifestEntry

# the window length of every shared campaign: the Dask test's manifests use it too, so that its
# runs and the resumed campaign's are the same entries
WINDOW_S = 3.0


@dataclass(frozen=True)
class ResumedCampaign:
    manifest: Path
    entries: list[ManifestEntry]
    ds: Path
    first_done: list[str]  # the runs done before the kill
    before: dict[str, bytes]  # their shards as they were at the kill
    resume: subprocess.CompletedProcess  # the resuming `campaign run`


@pytest.fixture(scope="session")
def resumed_campaign(tmp_path_factory) -> ResumedCampaign:
    tmp = tmp_path_factory.mktemp("resumed")
    m = tmp / "m.jsonl"
    entries = write_manifest(m, n=3, window_s=WINDOW_S)
    ds = tmp / "ds"
    proc = subprocess.Popen([sys.executable, "-m", "uavcas.cli", "campaign", "run", "--manifest", str(m), "--out",
                             str(ds)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if any((ds / "runs").glob("*/DONE")):
            break
        time.sleep(0.2)
    first_done = sorted(p.parent.name for p in (ds / "runs").glob("*/DONE"))
    os.killpg(proc.pid, signal.SIGKILL)  # the whole campaign, emulation included, dies at once
    proc.wait()
    before = {i: (ds / "shards" / f"{i}.parquet").read_bytes() for i in first_done}
    subprocess.run([sys.executable, "-m", "uavcas.cli", "clean"], capture_output=True, timeout=60)
    resume = cli("campaign", "run", "--manifest", str(m), "--out", str(ds), timeout=300)
    return ResumedCampaign(m, entries, ds, first_done, before, resume)
