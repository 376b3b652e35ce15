"""A run whose fidelity audit failed: kept and flagged, or retried like a failed run (option)."""

from __future__ import annotations

import pytest

from uavcas.campaign.layout import CampaignError
from uavcas.campaign.retry import Retries
from uavcas.campaign.run import run_campaign
from uavcas.campaign.task import RunOutcome


def _out(retry: bool, ok: bool = True) -> RunOutcome:
    return RunOutcome(index=3, ok=ok, host="h", wall_s=1.0, fidelity="fail" if retry else "pass", retry=retry)


def test_a_fidelity_failure_is_retried_then_kept():
    seen = []
    r = Retries(1, on_retry=lambda out, attempt: seen.append(attempt))
    assert r.started(3) == 1 and r.again(_out(retry=True))
    assert r.started(3) == 2 and not r.again(_out(retry=True))  # out of tries: this one is kept, flagged
    assert seen == [1]
    assert r.started(4) == 1 and not Retries(1).again(_out(retry=False))
    assert "retry" in _out(retry=True).summary() and _out(retry=True).summary()["fidelity"] == "fail"


def test_an_unknown_policy_is_refused_before_anything_is_made(tmp_path):
    with pytest.raises(CampaignError, match="--fidelity must be one of flag, retry"):
        run_campaign([], tmp_path / "ds", fidelity="ignore")
    assert not (tmp_path / "ds").exists()
