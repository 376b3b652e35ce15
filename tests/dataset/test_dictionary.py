"""The data dictionary describes every column a dataset holds, and everything that describes
columns (card, Parquet field metadata, docs/formats.md, `uavcas info --columns`) reads it."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from uavcas import vocabulary
from uavcas.cli import app
from uavcas.dataset import dictionary, dictionary_docs
from uavcas.dataset.parquet import arrow_schema
from uavcas.dataset.store import extract_run
from uavcas.flows.standards import names
from uavcas.views import view, views

FLOWS = view("5tuple")
DOCS = Path(__file__).resolve().parents[2] / "docs" / "formats.md"


def _described_dataset(ds: Path) -> None:
    """Every column of flows.parquet: an entry in the card and unit + meaning in its field metadata."""
    card = json.loads((ds / "dataset.json").read_text())
    fields = pq.read_schema(ds / "flows.parquet")
    assert list(card["columns"]) == fields.names
    for f in fields:
        entry = card["columns"][f.name]
        assert entry["meaning"] and entry["unit"] and entry["dtype"] == str(f.type), f.name
        assert f.metadata == {b"unit": entry["unit"].encode(), b"meaning": entry["meaning"].encode()}, f.name


@pytest.mark.parametrize("view", ["5tuple", "window-host"])
def test_every_column_of_an_extracted_dataset_is_described(synth_run_dir, tmp_path, view):
    ds = tmp_path / "ds"
    extract_run(synth_run_dir, ds, view=view)
    _described_dataset(ds)


def test_every_schema_column_of_every_standard_and_view_is_described():
    for std in names():
        for spec in views():
            sch = arrow_schema(std, context=True, view=spec.name)
            cols = dictionary.columns(sch, std, spec)
            assert [c.name for c in cols] == sch.names and all(c.meaning and c.unit for c in cols)
    units = {c.name: c.unit for c in dictionary.columns(arrow_schema("cic"), "cic", FLOWS)}
    assert units["Flow Duration"] == "us" and units["Flow Bytes/s"] == "bytes/s" and units["duration_s"] == "s"
    assert dictionary.describe("Flow Duration", "paper", FLOWS)[0] == "s"


def test_a_column_without_an_entry_is_an_error():
    with pytest.raises(dictionary.DictionaryError, match="'Flow Wobble'"):
        dictionary.describe("Flow Wobble", "cic", FLOWS)
    with pytest.raises(dictionary.DictionaryError):
        dictionary.describe("packets_out", "cic", FLOWS)  # an episode column is not a flow column
    with pytest.raises(dictionary.DictionaryError):
        dictionary.describe("ctx_src_bogus", "cic", FLOWS)


def test_family_columns_follow_the_vocabulary():
    for fam in vocabulary.FAMILIES:
        assert fam in dictionary.describe(f"attack_packets_{fam}", "cic", FLOWS)[1]
        assert vocabulary.FAMILY_CLASS[fam] in dictionary.describe(f"label_{fam}", "cic", FLOWS)[1]
    for effect in vocabulary.EFFECTS:
        assert effect in dictionary.describe("seq_effect", "cic", FLOWS)[1]


def test_docs_section_is_the_generated_one():
    text = DOCS.read_text()
    assert dictionary_docs.with_docs_section(text) == text, ("run: python -m uavcas.dataset.dictionary_docs "
                                                             "docs/formats.md")


def test_info_columns_lists_every_column_with_unit_and_meaning(synth_run_dir, tmp_path):
    ds = tmp_path / "ds"
    extract_run(synth_run_dir, ds)
    r = CliRunner().invoke(app, ["info", str(ds), "--columns"])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    for name, entry in json.loads((ds / "dataset.json").read_text())["columns"].items():
        row = next((ln for ln in lines if ln.split("\t")[0] == name), None)
        assert row is not None, name
        assert row.split("\t")[1:] == [entry["dtype"], entry["unit"], entry["meaning"]]
