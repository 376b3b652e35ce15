"""Campaign axes, presets (paper, medium, quick), the seeded permutation and shard selection.

The paper preset is the Cartesian product of Table 'tab:config_space': 16 attack compositions x
{5,10,15,20} UAVs x {logdist,3gpp} x {spiral,grid,hover_transit,random} x {10,30} dBm, with
2 BSs, image payload, adaptive MCS and a -95 dBm noise floor: 1,024 configurations. `index` is
the position in that product (compositions vary slowest); `position` is where the seeded
permutation put it, so that any prefix or shard covers every axis proportionally.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass

import numpy as np

from uavcas import seeding

from .codec import Scenario, ScenarioError, parse

REPLAY_CONSERVATIVE = "replay=50,200,10,5,inc"
REPLAY_AGGRESSIVE = "replay=100,100,20,3,rand"

# Table 'tab:collab_taxonomy' of the paper, tokens in canonical order.
PAPER_COMPOSITIONS: tuple[str, ...] = (
    "benign",
    "dos=1000",
    "ddos=1000",
    "blackhole",
    "wormhole",
    REPLAY_CONSERVATIVE,
    REPLAY_AGGRESSIVE,
    "blackhole+dos=1000",
    "blackhole+ddos=1000",
    "dos=1000+wormhole",
    "ddos=1000+wormhole",
    "blackhole+wormhole",
    f"blackhole+{REPLAY_CONSERVATIVE}",
    f"ddos=1000+{REPLAY_CONSERVATIVE}",
    f"dos=1000+{REPLAY_CONSERVATIVE}",
    f"{REPLAY_CONSERVATIVE}+wormhole",
)


@dataclass(frozen=True)
class ManifestEntry:
    index: int  # position in the unpermuted preset
    position: int  # position in the seeded permutation
    config: str
    seed: int  # the run's own seed, derived from (campaign seed, index)
    windows: int
    window_s: float
    rounds: int = 1  # attack rounds per run (twin.schedule); stored as "episodes", its old name

    def to_dict(self) -> dict:
        return {
            "index": self.index,
            "position": self.position,
            "config": self.config,
            "seed": self.seed,
            "windows": self.windows,
            "window_s": self.window_s,
            "episodes": self.rounds,  # the stored key keeps its old name: manifests written before read alike
        }

    @classmethod
    def from_dict(cls, data: dict) -> ManifestEntry:
        """The entry `to_dict` gave (what a Dask task carries): its stored key `episodes` is `rounds`."""
        data = dict(data)
        if "episodes" in data:
            data["rounds"] = data.pop("episodes")
        return cls(**data)


@dataclass(frozen=True)
class Preset:
    name: str
    configs: tuple[str, ...]
    windows: int
    window_s: float
    rounds: int = 1


def _paper_configs() -> tuple[str, ...]:
    out = []
    for comp, n, pl, mission, tx in itertools.product(
        PAPER_COMPOSITIONS, (5, 10, 15, 20), ("logdist", "3gpp"),
        ("spiral", "grid", "hover_transit", "random"), (10, 30),
    ):
        out.append(f"{comp}-{n}-2-image-{pl}-adaptive-{mission}-{tx}-95")
    return tuple(out)


# The quick preset is the default main job: small swarms, short runs, and every kind of class a
# first look needs (benign, a flood, stealth attacks, a collaborative pair, both path-loss models),
# on UAV traffic: payload `mixed` (MAVLink v2, H.264 video and the image fetches; issue 23). The
# paper preset keeps the paper's `image` traffic.
QUICK_CONFIGS: tuple[str, ...] = (
    "benign-5-2-mixed-logdist-adaptive-random-30-95",
    "dos=1000-5-2-mixed-logdist-adaptive-spiral-30-95",
    "blackhole-5-2-mixed-3gpp-adaptive-grid-30-95",
    # 30 dBm: at 10 dBm no UAV of this swarm has a usable detour around the victim's route, so the
    # wormhole changed nothing (tests/scenario/test_campaign.py checks every quick attack acts)
    "wormhole-6-2-mixed-logdist-adaptive-hover_transit-30-95",
    f"{REPLAY_AGGRESSIVE}-5-2-mixed-logdist-adaptive-random-30-95",
    "blackhole+dos=1000-6-2-mixed-3gpp-adaptive-random-10-95",
)

# The families added after the paper (issue 24), each alone and in two compositions with the
# paper's families. jamming: a 20 dBm ground jammer beside the victim's route; gps_spoof: the
# victim's position reports drift 3 m/s towards a lure; mavlink_inject: forged RTL commands.
NEW_FAMILY_COMPOSITIONS: tuple[str, ...] = (
    "jamming=20",
    "blackhole+jamming=20",
    "dos=1000+jamming=20",
    "gps_spoof=3",
    "gps_spoof=3+wormhole",
    "ddos=1000+gps_spoof=3",
    "mavlink_inject=rtl",
    "blackhole+mavlink_inject=rtl",
    f"mavlink_inject=rtl+{REPLAY_CONSERVATIVE}",
)

# The medium preset is the benchmark's dataset: the paper's 16 compositions and the 9 of the new
# families, each in 4 channel settings (100 runs of 12 windows), on UAV traffic (payload `mixed`:
# MAVLink, video and images; gps_spoof and mavlink_inject act on MAVLink). Path loss x TX power
# is a full 2 x 2 design over the settings; mission and swarm size take one value per setting
# (4 settings cannot cross two 4-valued axes), so each is confounded with the setting, which
# `uavcas analyze axes` reports. Holding out one setting (e.g. mission=random) leaves every
# composition in 3 seen settings for the cross-condition protocol. The paper's compositions come
# first (runs 0-63), the new families' after them.
MEDIUM_SETTINGS: tuple[tuple[int, str, str, int], ...] = (  # (n_uav, pathloss, mission, tx_dbm)
    (5, "logdist", "spiral", 30),
    (6, "3gpp", "grid", 10),
    (8, "3gpp", "hover_transit", 30),
    (10, "logdist", "random", 10),
)
MEDIUM_PAYLOAD = "mixed"
# Three attack rounds per run (each 10-16.7 s, >= 5 s apart, on a victim drawn afresh): a class
# lives on its victim in ~4 windows per round, so one round gave ~16 window-host rows per
# collaborative class over its 4 runs; three give ~45 (the benchmark asks 30 from 2 runs).
MEDIUM_ROUNDS = 3


def _medium_configs(compositions: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(
        f"{comp}-{n}-2-{MEDIUM_PAYLOAD}-{pl}-adaptive-{mission}-{tx}-95"
        for n, pl, mission, tx in MEDIUM_SETTINGS
        for comp in compositions
    )


# the medium design's runs over the paper's 16 compositions (`uavcas dataset synth` cycles them)
MEDIUM_PAPER_CONFIGS = _medium_configs(PAPER_COMPOSITIONS)


PRESETS: dict[str, Preset] = {
    "paper": Preset("paper", _paper_configs(), windows=12, window_s=5.0),
    "medium": Preset("medium", MEDIUM_PAPER_CONFIGS + _medium_configs(NEW_FAMILY_COMPOSITIONS), windows=12,
                     window_s=5.0, rounds=MEDIUM_ROUNDS),
    "quick": Preset("quick", QUICK_CONFIGS, windows=3, window_s=5.0),
}


def run_seed(campaign_seed: int, index: int) -> int:
    """A run's seed: stable in (campaign seed, index), independent of order and sharding."""
    return seeding.child_seed(campaign_seed, index)


def permutation(n: int, seed: int) -> np.ndarray:
    return seeding.generator(seed).permutation(n)


_SHARD = re.compile(r"^(0|[1-9][0-9]*)/([1-9][0-9]*)$")


def parse_shard(text: str) -> tuple[int, int]:
    m = _SHARD.match(text.strip())
    if not m:
        raise ValueError(f"shard: expected K/N with 0 <= K < N, got {text!r}")
    k, n = int(m.group(1)), int(m.group(2))
    if k >= n:
        raise ValueError(f"shard: K must be < N, got {text!r}")
    return k, n


def manifest(
    preset: str | Preset = "paper", seed: int = 0, shard: tuple[int, int] | None = None
) -> list[ManifestEntry]:
    """Entries in permutation order; a shard K/N is the K-th of N contiguous, near-equal slices."""
    p = PRESETS[preset] if isinstance(preset, str) else preset
    for c in p.configs:  # a preset is data; refuse it loudly if it is not valid
        parse(c)
    order = permutation(len(p.configs), seed)
    entries = [
        ManifestEntry(
            index=int(idx),
            position=pos,
            config=p.configs[idx],
            seed=run_seed(seed, int(idx)),
            windows=p.windows,
            window_s=p.window_s,
            rounds=p.rounds,
        )
        for pos, idx in enumerate(order)
    ]
    return select_shard(entries, shard) if shard is not None else entries


def select_shard(entries: list[ManifestEntry], shard: tuple[int, int]) -> list[ManifestEntry]:
    """The K-th of N contiguous, near-equal slices of `entries` (in their given order)."""
    k, n = shard
    bounds = np.linspace(0, len(entries), n + 1).round().astype(int)
    return entries[bounds[k] : bounds[k + 1]]


__all__ = [
    "ManifestEntry",
    "PAPER_COMPOSITIONS",
    "PRESETS",
    "Preset",
    "Scenario",
    "ScenarioError",
    "manifest",
    "parse_shard",
    "permutation",
    "run_seed",
    "select_shard",
]
