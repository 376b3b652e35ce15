"""A real campaign's dataset (root), published: mlcroissant validates its Croissant file and reads
its records, and the card lists every column with its unit.

The dataset is the session's shared killed-and-resumed campaign (`helpers.root_campaigns`: three
emulated runs, benign, a SYN flood and a blackhole), so this test adds the publication alone to
the suite's time; it published a whole quick campaign before (564 s, most of it mlcroissant
reading 28k records one by one). mlcroissant reads records one by one (~100 a second here), so
this test reads the first `SAMPLE` and checks each against the shards; reading *every* record
and matching it is `tests/dataset/test_publish.py`'s job, on a small dataset. The quick preset
itself is the README's main job.
"""

from __future__ import annotations

import itertools
import re
import subprocess
import sys

import pyarrow.parquet as pq
import pytest

from uavcas.dataset.dictionary import describe
from uavcas.dataset.parquet import read_flows
from uavcas.dataset.store import read_card
from uavcas.views import view

SAMPLE = 300  # records read back through mlcroissant (the campaign has thousands)


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
    df = read_flows(ds / "flows.parquet")
    assert len(df) == read_card(ds)["n_flows"] > SAMPLE
    records = list(itertools.islice(mlc.Dataset(jsonld=croissant).records("flows"), SAMPLE))
    rows = df.set_index(["run_id", "flow_id"])
    assert len(records) == SAMPLE
    for rec in records:  # each record read is a row of the shards, with its values
        row = rows.loc[(rec["flows/run_id"].decode(), int(rec["flows/flow_id"]))]
        assert rec["flows/label"].decode() == row["label"] and rec["flows/packets"] == row["packets"]
        assert rec["flows/Flow_Duration"] == row["Flow Duration"]
    # the card: every column of the shards with its dtype and unit
    text = (pub / "README.md").read_text()
    card = {m.group(1): (m.group(2), m.group(3))
            for m in re.finditer(r"^\| `([^`]+)` \| ([^|]+) \| ([^|]+) \|", text, re.M)}
    for f in pq.read_schema(ds / "flows.parquet"):
        unit = describe(f.name, "cic", view("5tuple"))[0]
        assert card[f.name][0].strip() == str(f.type) and card[f.name][1].strip() == unit, f.name
    # every class the campaign holds is in the card
    labels = set(pq.read_table(ds / "flows.parquet", columns=["label"]).column("label").to_pylist())
    assert labels and all(c in text for c in labels), labels
