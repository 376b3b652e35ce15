"""`campaign.layout.write_manifest` / `read_manifest`: the manifest file of `uavcas campaign manifest`."""

from __future__ import annotations

import json

from uavcas.campaign import read_manifest, write_manifest
from uavcas.campaign.layout import manifest_text
from uavcas.scenario import manifest


def test_a_written_manifest_reads_back_entry_for_entry(tmp_path):
    entries = manifest("quick", seed=3)
    path = write_manifest(tmp_path / "m.jsonl", entries)
    assert read_manifest(path) == entries
    lines = path.read_text().splitlines()
    assert len(lines) == len(entries) and path.read_text() == manifest_text(entries)
    assert all(list(json.loads(line)) == sorted(json.loads(line)) for line in lines)  # keys sorted: stable diffs


def test_attack_rounds_keep_their_stored_name(tmp_path):
    """A manifest stores an entry's attack rounds under their old key, "episodes": files written
    before the rename read alike, and new ones are byte-identical to what they were."""
    entries = manifest("medium", seed=0)[:2]
    path = write_manifest(tmp_path / "m.jsonl", entries)
    stored = [json.loads(line) for line in path.read_text().splitlines()]
    assert all(d["episodes"] == 3 and "rounds" not in d for d in stored)
    assert [e.rounds for e in read_manifest(path)] == [3, 3]
