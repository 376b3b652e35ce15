"""The quick preset's dataset, emulated for real (root), published: mlcroissant validates its
Croissant file and reads every record, and the card lists every column with its unit."""

from __future__ import annotations

import re
import subprocess
import sys

import pyarrow.parquet as pq
import pytest

from uavcas.dataset.dictionary import describe
from uavcas.dataset.store import read_card
from uavcas.views import view

# a real quick campaign (about 150 s quiet), then mlcroissant reads its ~28k records row by row
# (pandas apply per field): past the suite's 600 s on a loaded machine (it timed out so once)
pytestmark = [pytest.mark.root, pytest.mark.slow, pytest.mark.timeout(1800)]


def _cli(*args, timeout: int) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "uavcas.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def test_the_quick_dataset_publishes_a_croissant_file_mlcroissant_validates(tmp_path):
    mlc = pytest.importorskip("mlcroissant")
    ds, pub = tmp_path / "quick", tmp_path / "pub"
    r = _cli("campaign", "run", "--preset", "quick", "--out", ds, "--no-report", timeout=900)
    assert r.returncode == 0, r.stderr[-2000:]
    r = _cli("publish", ds, "--out", pub, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "croissant.json valid (mlcroissant" in r.stdout and "0 warning(s)" in r.stdout, r.stdout
    croissant = pub / "croissant.json"
    records = list(mlc.Dataset(jsonld=croissant).records("flows"))
    assert len(records) == read_card(ds)["n_flows"] > 0
    # the card: every column of the shards with its dtype and unit
    text = (pub / "README.md").read_text()
    rows = {m.group(1): (m.group(2), m.group(3))
            for m in re.finditer(r"^\| `([^`]+)` \| ([^|]+) \| ([^|]+) \|", text, re.M)}
    for f in pq.read_schema(ds / "flows.parquet"):
        unit = describe(f.name, "cic", view("5tuple"))[0]
        assert rows[f.name][0].strip() == str(f.type) and rows[f.name][1].strip() == unit, f.name
