"""A feature standard is added by dropping one module into `uavcas.flows.standards`: a temporary
copy of the package with one new module, and the registry, the CLI choices, the flows it computes
and the dataset card's column entries all know it, with no other edit."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from helpers.pcapgen import http_session, write
from helpers.plugin import check_ok, package_with

PLUGIN = '''
"""Feature standard `tiny` (test only): a flow's packets and frame bytes."""
import numpy as np

from .base import FeatureStandard
from .registry import register

COLUMNS = ("Tiny Packets", "Tiny Bytes")


def compute(fp):
    n = fp.flows.n_flows
    return {"Tiny Packets": np.bincount(fp.flows.flow, minlength=n).astype(np.float64),
            "Tiny Bytes": np.bincount(fp.flows.flow, weights=fp.ordered("frame_len"), minlength=n)}


STANDARD = register(FeatureStandard(
    name="tiny", columns=COLUMNS, units={"Tiny Packets": "packets", "Tiny Bytes": "bytes"},
    meanings={"Tiny Packets": "packets of the flow", "Tiny Bytes": "frame bytes of the flow"},
    source="test only", summary="two counts, no time", compute=compute,
    episode_summary={"Tiny Bytes": "tiny_bytes"}))
'''

CHECK = '''
import sys
import uavcas
from uavcas.dataset.dictionary import card_columns, describe
from uavcas.dataset.parquet import arrow_schema
from uavcas.flows.standards import names, standard
from uavcas.views import view

assert uavcas.__file__.startswith(sys.argv[1]), uavcas.__file__
assert "tiny" in names() and standard("tiny").source == "test only"
cols = card_columns(arrow_schema("tiny"), "tiny", view("5tuple"))
assert cols["Tiny Bytes"]["unit"] == "bytes", cols["Tiny Bytes"]
assert cols["Tiny Packets"]["meaning"].startswith("packets of the flow"), cols["Tiny Packets"]
assert "Flow Duration" not in cols  # the card lists this standard's columns, not another's
assert describe("tiny_bytes_max", "tiny", view("window-host"))[0] == "bytes"
print("ok")
'''


@pytest.fixture(scope="module")
def plugged(tmp_path_factory) -> tuple[Path, dict]:
    root = tmp_path_factory.mktemp("plug")
    return root, package_with(root, "flows/standards/tiny.py", PLUGIN)


def test_a_dropped_in_standard_is_in_the_registry_and_the_card(plugged):
    check_ok(CHECK, *plugged)


@pytest.mark.slow  # 8 s on 2 cores
def test_a_dropped_in_standard_is_offered_and_computed_by_the_cli(plugged, tmp_path):
    root, env = plugged
    r = subprocess.run([sys.executable, "-m", "uavcas", "flows", "--help"], capture_output=True, text=True, env=env,
                       timeout=120)
    assert r.returncode == 0 and "tiny" in r.stdout and "two counts, no time" in r.stdout, r.stdout
    pk = http_session()
    pcap = write(tmp_path / "h.pcap", pk)
    out = tmp_path / "f.csv"
    r = subprocess.run([sys.executable, "-m", "uavcas", "flows", str(pcap), "--features", "tiny", "--format", "csv",
                        "--out", str(out)], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    row = pd.read_csv(out).iloc[0]
    assert row["Tiny Packets"] == len(pk) and row["Tiny Bytes"] == sum(len(p) for p in pk)
    assert "Flow Duration" not in row.index
