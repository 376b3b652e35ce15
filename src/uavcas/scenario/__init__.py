"""Scenario strings (the paper's 9 fields) and campaign presets."""

from .campaign import PRESETS, ManifestEntry, manifest, parse_shard, run_seed, select_shard
from .codec import Scenario, ScenarioError, canonical, parse

__all__ = [
    "ManifestEntry",
    "PRESETS",
    "Scenario",
    "ScenarioError",
    "canonical",
    "manifest",
    "parse",
    "parse_shard",
    "run_seed",
    "select_shard",
]
