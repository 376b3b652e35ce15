"""Campaign bookkeeping that needs no emulation: manifests, DONE markers, orphan shards."""

import json

import pytest

from uavcas.campaign import CampaignDir, CampaignError, Extraction, read_manifest
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


def test_a_resumed_campaign_keeps_its_view_and_termination(tmp_path):
    cdir = CampaignDir(tmp_path)
    cdir.bind_extraction(Extraction(view="window-host"))
    cdir.bind_extraction(Extraction(view="window-host", termination="connection"))  # the same (default): resume
    with pytest.raises(CampaignError, match="--view window-host --termination connection, not --view 5tuple"):
        cdir.bind_extraction(Extraction(view="5tuple"))
    with pytest.raises(CampaignError, match="not --view window-host --termination cic"):
        cdir.bind_extraction(Extraction(view="window-host", termination="cic"))
    with pytest.raises(ValueError, match="--termination: the hostpair view has no termination policy"):
        Extraction(view="hostpair", termination="cic")
    with pytest.raises(ValueError, match="--view: 'bogus' is not one of"):
        Extraction(view="bogus")


def _shard_meta(cdir, index, meta):
    import pyarrow as pa
    import pyarrow.parquet as pq

    cdir.run_dir(index).mkdir(parents=True)
    cdir.mark_done(index, {})
    cdir.shard_path(index).parent.mkdir(exist_ok=True)
    t = pa.table({"x": [1]}).replace_schema_metadata({b"uavcas": json.dumps(meta).encode()})
    pq.write_table(t, cdir.shard_path(index))


def test_a_campaign_from_before_the_extraction_was_recorded_is_checked_by_its_shards(tmp_path):
    cdir = CampaignDir(tmp_path)
    _shard_meta(cdir, 0, {"view": "5tuple", "flow_rules": {"termination": "connection"}})
    with pytest.raises(CampaignError, match="--view 5tuple --termination connection, not --view hostpair"):
        cdir.bind_extraction(Extraction(view="hostpair"))
    assert not cdir.extraction_path.exists()
    cdir.bind_extraction(Extraction(view="5tuple"))
    assert json.loads(cdir.extraction_path.read_text()) == {"view": "5tuple", "termination": "connection"}
    # a shard cut by the rules before the termination policies records none: refused
    old = CampaignDir(tmp_path / "old")
    _shard_meta(old, 0, {"view": "5tuple", "flow_rules": {"fin_rst": True}})
    with pytest.raises(CampaignError, match="--termination None, not --view 5tuple --termination connection"):
        old.bind_extraction(Extraction())


def test_a_resumed_campaign_keeps_its_mavlink_signing(tmp_path):
    cdir = CampaignDir(tmp_path)
    cdir.bind_emulation(mavlink_signing=True)
    cdir.bind_emulation(mavlink_signing=True)  # resume
    assert json.loads(cdir.emulation_path.read_text()) == {"mavlink_signing": True}
    with pytest.raises(CampaignError, match="emulated with --mavlink-signing; resume it with that"):
        cdir.bind_emulation(mavlink_signing=False)
    # a campaign with runs done before the option was recorded had no signing
    old = CampaignDir(tmp_path / "old")
    _shard_meta(old, 0, {"view": "5tuple"})
    with pytest.raises(CampaignError, match="emulated with --no-mavlink-signing"):
        old.bind_emulation(mavlink_signing=True)
    old.bind_emulation(mavlink_signing=False)
    assert json.loads(old.emulation_path.read_text()) == {"mavlink_signing": False}
