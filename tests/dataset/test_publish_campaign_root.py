"""A real campaign's dataset (root), published: mlcroissant validates its Croissant file and reads
every record, and the card lists every column with its unit.

The dataset is the session's shared killed-and-resumed campaign (`helpers.root_campaigns`: three
emulated runs, benign, a SYN flood and a blackhole), so this test adds the publication alone to
the suite's time; it published a whole quick campaign before (564 s, most of it mlcroissant
reading 28k records one by one). The quick preset itself is the README's main job.
"""

from __future__ import annotations

import re
import subprocess
import sys

import pyarrow.parquet as pq
import pytest

from uavcas.dataset.dictionary import describe
from uavcas.dataset.store import read_card
from uavcas.views import view


def _cli(*args, timeout: int) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "uavcas.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def test_a_real_campaign_publishes_a_croissant_file_mlcroissant_validates(resumed_campaign, tmp_path):
    mlc = pytest.importorskip("mlcroissant")
    ds, pub = resumed_campaign.ds, tmp_path / "pub"
    assert resumed_campaign.resume.returncode == 0, resumed_campaign.resume.stderr[-2000:]
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
    # every class the campaign holds is in the card
    labels = set(pq.read_table(ds / "flows.parquet", columns=["label"]).column("label").to_pylist())
    assert labels and all(c in text for c in labels), labels
