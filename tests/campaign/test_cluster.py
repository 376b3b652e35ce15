"""`campaign run --scheduler` without a cluster (no root needed): refused in one line."""

from __future__ import annotations

import pytest

from helpers.campaign_runs import cli, free_port, write_manifest

pytestmark = [pytest.mark.slow]  # the client tries to connect for its 20 s


def test_an_unreachable_scheduler_is_one_line(tmp_path):
    m = tmp_path / "m.jsonl"
    write_manifest(m, n=1, window_s=3.0)
    r = cli("campaign", "run", "--manifest", str(m), "--out", str(tmp_path / "ds"), "--scheduler",
            f"tcp://127.0.0.1:{free_port()}", timeout=60)
    assert r.returncode != 0
    assert "error: cannot reach the Dask scheduler at tcp://127.0.0.1:" in r.stderr, r.stderr[-2000:]
    assert "Traceback" not in r.stderr
