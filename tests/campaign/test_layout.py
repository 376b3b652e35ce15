"""Campaign bookkeeping that needs no emulation: manifests, DONE markers, orphan shards."""

import json

import pytest

from uavcas.campaign import CampaignDir, CampaignError, read_manifest
from uavcas.scenario import manifest


def test_manifest_file_round_trip_and_errors(tmp_path):
    entries = manifest("quick", seed=3)
    p = tmp_path / "m.jsonl"
    p.write_text("".join(json.dumps(e.to_dict()) + "\n" for e in entries))
    assert read_manifest(p) == entries
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"index": 0, "config": "nope", "seed": 1}\n')
    with pytest.raises(CampaignError, match=r"bad.jsonl:1"):
        read_manifest(bad)
    dup = tmp_path / "dup.jsonl"
    line = json.dumps(entries[0].to_dict()) + "\n"
    dup.write_text(line + line)
    with pytest.raises(CampaignError, match="duplicate"):
        read_manifest(dup)


def test_a_directory_keeps_one_campaign(tmp_path):
    cdir = CampaignDir(tmp_path)
    cdir.bind_manifest(manifest("quick", seed=1))
    cdir.bind_manifest(manifest("quick", seed=1))  # same campaign: fine (resume)
    with pytest.raises(CampaignError, match="another --out"):
        cdir.bind_manifest(manifest("quick", seed=2))


def test_only_done_runs_keep_their_shards(tmp_path):
    cdir = CampaignDir(tmp_path)
    for i in (0, 1, 2):
        cdir.run_dir(i).mkdir(parents=True)
        cdir.shard_path(i).parent.mkdir(exist_ok=True)
        cdir.shard_path(i).write_bytes(b"x")
    cdir.mark_done(1, {"index": 1})
    removed = cdir.prune_orphan_shards()
    assert sorted(p.name for p in removed) == ["0.parquet", "2.parquet"]
    assert cdir.is_done(1) and cdir.shard_path(1).exists()
    cdir.reset(1)
    assert not cdir.is_done(1) and not cdir.shard_path(1).exists()


def test_a_resumed_campaign_keeps_its_view(tmp_path):
    cdir = CampaignDir(tmp_path)
    cdir.bind_view("window-host")
    cdir.bind_view("window-host")  # the same view: resume
    with pytest.raises(CampaignError, match="--view window-host, not 5tuple"):
        cdir.bind_view("5tuple")


def test_a_campaign_from_before_the_view_was_recorded_is_checked_by_its_shards(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    cdir = CampaignDir(tmp_path)
    cdir.run_dir(0).mkdir(parents=True)
    cdir.mark_done(0, {})
    cdir.shard_path(0).parent.mkdir()
    t = pa.table({"x": [1]}).replace_schema_metadata({b"uavcas": json.dumps({"view": "5tuple"}).encode()})
    pq.write_table(t, cdir.shard_path(0))
    with pytest.raises(CampaignError, match="--view 5tuple, not hostpair"):
        cdir.bind_view("hostpair")
    assert not cdir.view_path.exists()
    cdir.bind_view("5tuple")
    assert cdir.view_path.read_text() == "5tuple\n"
