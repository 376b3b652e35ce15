"""Scenario strings (the paper's 9 fields) and campaign presets."""

from .campaign import PRESETS, ManifestEntry, manifest, parse_shard, run_seed, select_shard
from .codec import Blackhole, Flood, Replay, Scenario, ScenarioError, Wormhole, parse

__all__ = [
    "Blackhole",
    "Flood",
    "ManifestEntry",
    "PRESETS",
    "Replay",
    "Scenario",
    "ScenarioError",
    "Wormhole",
    "manifest",
    "parse",
    "parse_shard",
    "run_seed",
    "select_shard",
]
