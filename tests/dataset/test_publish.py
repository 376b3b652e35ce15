"""`uavcas publish`: a dataset extracted from a run (two shards) round-trips through the published
directory: mlcroissant validates and reads croissant.json, Hugging Face `datasets` reads the
shards, both give the dataset's rows and values; the README card lists every column with its
unit, the classes, the labelling rules and the calibration data's licence."""

from __future__ import annotations

import hashlib
import json
import re

import numpy as np
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from uavcas.cli import app
from uavcas.dataset.dictionary import describe
from uavcas.dataset.parquet import read_flows
from uavcas.dataset.store import extract_run, read_card
from uavcas.schema import FAMILIES
from uavcas.views import view

runner = CliRunner()


def _run(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def ds(synth_run_dir, tmp_path_factory):
    """The synthetic run extracted twice under two run ids: two shards, real labelling rules."""
    out = tmp_path_factory.mktemp("pub") / "ds"
    extract_run(synth_run_dir, out, run_id="7")
    extract_run(synth_run_dir, out, run_id="8")
    return out


@pytest.fixture(scope="module")
def published(ds, tmp_path_factory):
    pytest.importorskip("mlcroissant")
    out = tmp_path_factory.mktemp("published") / "pub"
    r = _run("publish", ds, "--out", out, "--name", "uavcas-synth")
    assert r.exit_code == 0, r.output
    assert "croissant.json valid (mlcroissant" in r.output and "0 warning(s)" in r.output, r.output
    return out


def test_the_publication_holds_the_shards_card_croissant_and_readme(ds, published):
    assert sorted(p.name for p in (published / "shards").iterdir()) == ["7.parquet", "8.parquet"]
    assert {p.name for p in published.iterdir()} == {"shards", "dataset.json", "croissant.json", "README.md"}
    jsonld = json.loads((published / "croissant.json").read_text())
    assert jsonld["conformsTo"] == "http://mlcommons.org/croissant/1.1" and jsonld["name"] == "uavcas-synth"
    assert "Mishra" in jsonld["citeAs"] and jsonld["license"] == "CC-BY-4.0"
    # every file with the SHA-256 of what was written
    sums = {d["contentUrl"]: d["sha256"] for d in jsonld["distribution"] if d["@type"] == "cr:FileObject"}
    assert set(sums) == {"shards/7.parquet", "shards/8.parquet", "dataset.json"}
    for rel, sha in sums.items():
        assert hashlib.sha256((published / rel).read_bytes()).hexdigest() == sha, rel
    # one field per column of the data, with the dictionary's unit
    (rs,) = jsonld["recordSet"]
    schema = pq.read_schema(ds / "flows.parquet")
    assert [f["name"] for f in rs["field"]] == schema.names
    by_name = {f["name"]: f for f in rs["field"]}
    duration = by_name["Flow Duration"]
    assert duration["dataType"] == "cr:Float64" and "(unit: us)" in duration["description"]
    assert by_name["seq_size"]["cr:isArray"] is True and by_name["seq_size"]["dataType"] == "cr:Int32"
    assert by_name["label"]["dataType"] == "sc:Text"


@pytest.mark.slow  # 5 s on 2 cores
def test_mlcroissant_validates_and_reads_every_record(ds, published):
    mlc = pytest.importorskip("mlcroissant")
    from uavcas.dataset.croissant import validate

    assert validate(published / "croissant.json") == []
    df = read_flows(ds / "flows.parquet")
    records = list(mlc.Dataset(jsonld=published / "croissant.json").records("flows"))
    assert len(records) == len(df) == read_card(ds)["n_flows"]
    got = {(r["flows/run_id"].decode(), int(r["flows/flow_id"])): r for r in records}
    assert len(got) == len(df)
    for i in range(len(df)):
        row = df.iloc[i]
        rec = got[(row["run_id"], int(row["flow_id"]))]
        assert rec["flows/label"].decode() == row["label"]
        assert rec["flows/packets"] == row["packets"]
        assert rec["flows/Flow_Duration"] == row["Flow Duration"]
        assert np.array_equal(np.asarray(rec["flows/seq_size"]), np.asarray(row["seq_size"]))


def test_hugging_face_datasets_reads_the_shards(ds, published, tmp_path):
    datasets = pytest.importorskip("datasets")
    hf = datasets.load_dataset("parquet", data_files=str(published / "shards" / "*.parquet"), split="train",
                               cache_dir=str(tmp_path / "hf"))
    df = read_flows(ds / "flows.parquet")
    assert hf.num_rows == len(df)
    ours = df.sort_values(["run_id", "flow_id"]).reset_index(drop=True)
    theirs = hf.to_pandas().sort_values(["run_id", "flow_id"]).reset_index(drop=True)
    assert list(theirs.columns) == list(df.columns)
    assert (theirs["label"] == ours["label"]).all() and (theirs["bytes"] == ours["bytes"]).all()
    np.testing.assert_array_equal(theirs["Flow Bytes/s"].to_numpy(), ours["Flow Bytes/s"].to_numpy())  # NaN, inf too
    assert [list(x) for x in theirs["seq_dir"]] == [list(x) for x in ours["seq_dir"]]


def test_the_card_lists_every_column_with_its_unit(ds, published):
    text = (published / "README.md").read_text()
    rows = {m.group(1): (m.group(2), m.group(3))
            for m in re.finditer(r"^\| `([^`]+)` \| ([^|]+) \| ([^|]+) \|", text, re.M)}
    schema = pq.read_schema(ds / "flows.parquet")
    assert set(schema.names) <= set(rows)
    for f in schema:
        dtype, unit = rows[f.name]
        assert dtype.strip() == str(f.type) and unit.strip() == describe(f.name, "cic", view("5tuple"))[0], f.name


def test_the_card_has_classes_rules_fidelity_and_the_calibration_licence(ds, published):
    text = (published / "README.md").read_text()
    card = read_card(ds)
    for cls, n in card["class_counts"].items():
        if n:
            assert re.search(rf"^\| {re.escape(cls)} \| {n} \|$", text, re.M), cls
    for rule in card["label_rules"]:  # each family's truth and provoked rule, as the card has them
        for part in rule.split(" | ")[1:]:
            assert part.strip() in text
    for fam in FAMILIES:  # one item per family, the first one's split from the policy and precedence
        assert re.search(rf"^- {fam}: .+; provoked: ", text, re.M), fam
    assert re.search(r"^- ours: .+\(precedence [a-z_ >]+\)$", text, re.M)
    assert "unaudited 2" in text
    assert "MIT, as the re-publication's README states" in text and "AERPAW" in text
    # the synthetic run's plan names a profile this installation does not have
    assert "Twin profile `test`" in text and "not found here" in text


def test_the_calibrated_profile_is_traced_to_its_data():
    from uavcas.dataset.publish import calibration
    from uavcas.twin.profile import PAPER_PROFILE, default_profile, profile_sha256

    cal, paper = calibration({"profiles": {"calibrated": [profile_sha256(default_profile())],
                                           "paper": [profile_sha256(PAPER_PROFILE)]}})
    assert cal["fitted_on"]["tool"] == "uavcas calibrate all --seed 0" and cal["fitted_on"]["seed"] == 0
    assert cal["fitted_on"]["files"] == {"AFAR flights (mobility)": 28, "Maeng et al. LTE 3.51 GHz (path loss)": 6,
                                         "AERPAW multi-band channel sounder": 5}
    assert paper["fitted_on"] is None and "fitted on no data" in paper["note"]
    (other,) = calibration({"profiles": {"calibrated": ["0" * 64]}})
    assert other["fitted_on"] is None and "differs" in other["note"]


def test_bad_input_is_one_line_and_writes_nothing(ds, published, tmp_path):
    pytest.importorskip("mlcroissant")
    (tmp_path / "file").write_text("mine")
    for argv, needle in (
        (["publish", ds, "--out", published], "not empty"),
        (["publish", ds, "--out", tmp_path / "file"], "it is a regular file"),
        (["publish", tmp_path / "nothing", "--out", tmp_path / "no" / "p1"], "does not exist"),
        (["publish", tmp_path, "--out", tmp_path / "no" / "p2"], "not a dataset directory"),
        (["publish", published, "--out", tmp_path / "no" / "p3"], "no flows.parquet"),
    ):
        r = _run(*argv)
        assert r.exit_code == 2 and r.output.startswith("error: ") and r.output.count("\n") == 1, r.output
        assert needle in r.output, r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"] and (tmp_path / "file").read_text() == "mine"
    # an output directory is created with its missing parents (mkdir -p), once there is work to write
    assert _run("publish", ds, "--out", tmp_path / "new" / "pub").exit_code == 0
    assert (tmp_path / "new" / "pub" / "croissant.json").is_file()


def test_an_episode_dataset_is_published_as_host_windows(synth_run_dir, tmp_path):
    mlc = pytest.importorskip("mlcroissant")
    ep = tmp_path / "ep"
    extract_run(synth_run_dir, ep, view="window-host")
    r = _run("publish", ep, "--out", tmp_path / "pub")
    assert r.exit_code == 0, r.output
    records = list(mlc.Dataset(jsonld=tmp_path / "pub" / "croissant.json").records("host_windows"))
    assert len(records) == read_card(ep)["n_flows"] and {r["host_windows/view"] for r in records} == {b"window-host"}
    text = (tmp_path / "pub" / "README.md").read_text()
    assert "one per plan node per plan window" in text and "| `packets_out` | int64 | packets |" in text
