"""Real campaigns on the emulator (root): resume after a kill (on Dask: test_campaign_dask_root.py).

The killed and resumed campaign is the session's shared one (`helpers.root_campaigns`)."""

from __future__ import annotations

import pyarrow.parquet as pq


def test_killed_campaign_resumes_without_duplicates(resumed_campaign):
    c = resumed_campaign
    assert c.first_done, "no run finished before the kill"
    assert c.resume.returncode == 0, c.resume.stderr[-2000:]
    for i, data in c.before.items():  # finished runs are not redone
        assert (c.ds / "shards" / f"{i}.parquet").read_bytes() == data
    union = pq.read_table(c.ds / "flows.parquet")
    shards = [pq.read_table(c.ds / "shards" / f"{i}.parquet") for i in range(3)]
    assert union.num_rows == sum(s.num_rows for s in shards)  # every run exactly once
    assert sorted(set(union.column("run_id").to_pylist())) == [str(i) for i in range(3)]
    assert "already done" in c.resume.stdout
