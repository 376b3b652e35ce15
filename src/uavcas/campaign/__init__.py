"""Campaigns: a manifest of scenarios -> runs (local pool or Dask) -> one resumable dataset."""

from .layout import CampaignDir, CampaignError, read_manifest, write_manifest
from .run import CampaignResult, run_campaign
from .task import Extraction, RunOutcome, execute_entry

__all__ = [
    "CampaignDir",
    "CampaignError",
    "CampaignResult",
    "Extraction",
    "RunOutcome",
    "execute_entry",
    "read_manifest",
    "run_campaign",
    "write_manifest",
]
