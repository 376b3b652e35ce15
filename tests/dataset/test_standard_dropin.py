"""A feature standard is added by dropping one module into `uavcas.flows.standards` (issue 26).

A copy of the package gets a throwaway standard, `cicms`: cic's computation under other column
names, with its times in milliseconds. In a fresh interpreter that imports only the copy, the
registry finds it, the CLI offers it and refuses a name the registry lacks, and a dataset
extracted with it describes its columns with its own units: the card, the data dictionary and
the Parquet field metadata (not cic's microseconds, not paper's seconds).
"""

from __future__ import annotations

import json

import pyarrow.parquet as pq
import pytest

from helpers.plugin import package_copy, run_on

THROWAWAY = '''"""Throwaway standard for a test: cic's columns renamed, times in milliseconds."""

from __future__ import annotations

import numpy as np

from .base import FeatureStandard, FlowPackets
from .cic import STANDARD as CIC
from .registry import register

TIME = frozenset(c for c, unit in CIC.units.items() if unit == "us")


def _name(column: str) -> str:
    return f"ms {column}"


def compute(fp: FlowPackets) -> dict[str, np.ndarray]:
    got = CIC.compute(fp)
    return {_name(c): np.asarray(v, dtype=np.float64) / (1000.0 if c in TIME else 1.0) for c, v in got.items()}


STANDARD = register(FeatureStandard(
    name="cicms",
    columns=tuple(_name(c) for c in CIC.columns),
    units={_name(c): "ms" if c in TIME else unit for c, unit in CIC.units.items()},
    meanings={_name(c): meaning for c, meaning in CIC.meanings.items()},
    source="a test's copy of CICFlowMeter-4.0 in milliseconds",
    summary="cic in milliseconds",
    compute=compute,
    episode_summary={_name(c): stem.replace("_us", "_ms") for c, stem in CIC.episode_summary.items()},
))
'''


@pytest.mark.slow  # 18 s on 2 cores
def test_a_dropped_in_standard_is_registered_offered_and_described(synth_run_dir, tmp_path):
    pkg = package_copy(tmp_path, {"flows/standards/cicms.py": THROWAWAY})
    probe = run_on(pkg, "-c", "import uavcas, uavcas.flows.standards as s; print(uavcas.__file__); "
                            "print(' '.join(s.names()))")
    assert probe.returncode == 0, probe.stderr
    where, names = probe.stdout.splitlines()
    assert where.startswith(str(pkg)) and names.split() == ["cic", "cicms", "paper"]

    helped = run_on(pkg, "-m", "uavcas", "extract", "--help")
    assert helped.returncode == 0, helped.stderr
    helptext = " ".join(helped.stdout.replace("│", " ").split())  # help wrapped in a rich panel
    assert "cic|cicms|paper" in helptext and "cicms (cic in milliseconds)" in helptext
    refused = run_on(pkg, "-m", "uavcas", "extract", str(synth_run_dir), "--out", str(tmp_path / "no"),
                   "--features", "nope")
    assert refused.returncode != 0 and "cicms" in refused.stderr and not (tmp_path / "no").exists()

    ds = tmp_path / "ds"
    made = run_on(pkg, "-m", "uavcas", "extract", str(synth_run_dir), "--out", str(ds), "--features", "cicms")
    assert made.returncode == 0, made.stderr
    card = json.loads((ds / "dataset.json").read_text())
    feats = card["features"]
    assert feats["standard"] == "cicms" and "uavcas.flows.standards.cicms" in feats["source"]
    assert feats["units"]["ms Flow Duration"] == "ms" and feats["units"]["ms Flow IAT Mean"] == "ms"
    assert feats["units"]["ms Flow Bytes/s"] == "bytes/s"
    assert set(feats["units"]) == {f"ms {c}" for c in _cic_columns()}
    cols = card["columns"]
    assert cols["ms Flow Duration"]["unit"] == "ms" and cols["ms Flow Duration"]["meaning"].endswith("[cicms]")
    assert "Flow Duration" not in cols  # only its own columns, none of cic's or paper's
    field = pq.read_schema(ds / "flows.parquet").field("ms Flow Duration")
    assert field.metadata[b"unit"] == b"ms"
    listed = run_on(pkg, "-m", "uavcas", "info", str(ds), "--columns")
    assert listed.returncode == 0, listed.stderr
    row = next(line.split("\t") for line in listed.stdout.splitlines() if line.startswith("ms Flow IAT Max\t"))
    assert row[2] == "ms"

    # the values are cic's, in ms: the standard's compute is what the dataset holds
    ref = tmp_path / "ref"
    assert run_on(pkg, "-m", "uavcas", "extract", str(synth_run_dir), "--out", str(ref)).returncode == 0
    ours, cic = pq.read_table(ds / "flows.parquet").to_pandas(), pq.read_table(ref / "flows.parquet").to_pandas()
    assert len(ours) == len(cic) > 0
    assert ours["ms Flow Duration"].tolist() == (cic["Flow Duration"] / 1000.0).tolist()


def _cic_columns() -> tuple[str, ...]:
    from uavcas.flows.standards import standard

    return standard("cic").columns
