"""Plans stay byte-identical: the quick preset and the paper manifest's first 50 runs (seed 0)
against the digests recorded in tests/twin/data/plan_digests.json (`golden_plans.py` says when
and how to rewrite them)."""

from __future__ import annotations

import json

import pytest
from golden_plans import OUT, digests


@pytest.mark.slow  # 27 s on 2 cores
def test_plans_are_byte_identical_to_the_recorded_digests():
    want = json.loads(OUT.read_text())
    got = digests()
    assert set(got) == set(want)
    moved = sorted(k for k in want if got[k] != want[k])
    assert not moved, f"{len(moved)} plans changed: {moved[:5]}"
