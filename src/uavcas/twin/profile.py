"""Twin profiles: the calibrated numbers a plan is made with, by name, with their provenance.

A profile bundles the path-loss profile, the small-scale fading (Rician K(h)), the link-layer
settings, the mobility parameters, the BS mast height and the area. Names:

* ``calibrated`` (the default; also ``default``): shipped with uavcas as package data
  (``uavcas/twin/profiles/calibrated.json``), written by ``uavcas calibrate all
  --write-profile`` on the AERPAW data; its `provenance` names every data file with its
  sha256, the fit date, the uavcas version and the seed. Absolute path loss, mast 10 m (the
  AERPAW LW1 tower height the calibration recovers), K(h) measured on the same flights.
* ``paper``: the paper's numbers (path loss ``paper-anchored``: the paper's n(h), sigma(h)
  with PL0 anchored to free space; the paper's mobility table; 25 m masts, the TR 36.777 UMa
  BS height; K(h) of TR 36.777 Table B.1.2-2).
* any other name: ``NAME.json`` in the profile directory (`$UAVCAS_PROFILE_DIR`, else
  ``~/.local/share/uavcas/profiles``); or a path to a JSON file.

`profile_sha256` is the SHA-256 of the profile's canonical JSON (`TwinProfile.to_json`): plans,
runs and dataset cards record it beside the name, so a dataset says which numbers made it.
"""

from __future__ import annotations

import hashlib
import os
import re
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from uavcas.atomic import atomic_write_text
from uavcas.channel import PAPER_ANCHORED_PROFILE, TR36777_UMA_AV_K, KFactorProfile, LinkLayer, PathLossProfile
from uavcas.mobility import Area, MobilityProfile


class ProfileError(ValueError):
    """A profile that cannot be found or read; one line, names the file."""


class ChannelSettings(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    tx_gain_dbi: float = 0.0
    rx_gain_dbi: float = 0.0
    margin_db: float = 3.0  # threshold-selection margin above the MCS threshold (paper: 3 dB)
    d_corr_m: float = Field(50.0, gt=0)  # Gudmundson decorrelation distance (paper: 50 m)
    fc_ghz: float = Field(3.51, gt=0)
    link_layer: LinkLayer = LinkLayer()
    fading: KFactorProfile | None = TR36777_UMA_AV_K  # None: no small-scale fading
    selection: Literal["throughput", "threshold"] = "throughput"  # adaptive MCS rule (budget.link_chain)
    cca_dbm: float = -82.0  # carrier sense for airtime sharing (802.11-2020 17.3.10.6)


class DataFile(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    path: str  # relative to the data folder the calibration read
    sha256: str
    size_bytes: int


class Provenance(BaseModel):
    """Where a fitted profile's numbers come from."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    tool: str  # the command that fitted it
    uavcas_version: str
    fit_date_utc: str  # ISO 8601
    seed: int
    data_files: list[DataFile]
    notes: str = ""


class TwinProfile(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str = "paper"
    source: str = "built in: the paper's numbers, path loss anchored to free space at 1 m"
    area: Area = Area()
    bs_mast_m: float = Field(25.0, ge=0)  # BSs stand on the ground with a mast
    pathloss: PathLossProfile = PAPER_ANCHORED_PROFILE
    mobility: MobilityProfile = MobilityProfile()
    channel: ChannelSettings = ChannelSettings()
    backhaul_rate_mbps: float = Field(1000.0, gt=0)  # wired BS interconnect
    backhaul_delay_ms: float = Field(0.5, gt=0)
    provenance: Provenance | None = None

    def mobility_params(self, mission: str):
        return self.mobility.for_kind(mission)

    def chain_kwargs(self) -> dict:
        """The profile's settings of the link chain (`uavcas.channel.LinkChain.build`): antenna
        gains, MCS rule, link layer, fading, carrier sense. The scenario adds power, noise and
        modulation."""
        c = self.channel
        return {
            "tx_gain_dbi": c.tx_gain_dbi,
            "rx_gain_dbi": c.rx_gain_dbi,
            "margin_db": c.margin_db,
            "link_layer": c.link_layer,
            "fading": c.fading,
            "selection": c.selection,
            "cca_dbm": c.cca_dbm,
        }

    def channel_kwargs(self) -> dict:
        """`uavcas.channel.Channel`'s settings: the chain's, plus shadowing and carrier."""
        return {**self.chain_kwargs(), "d_corr_m": self.channel.d_corr_m, "fc_ghz": self.channel.fc_ghz}

    def to_json(self) -> str:
        return self.model_dump_json(indent=1) + "\n"


PAPER_PROFILE = TwinProfile()
DEFAULT_NAME = "calibrated"
PACKAGED = {"calibrated": "calibrated.json"}
BUILT_IN = ("default", "paper", *PACKAGED)
_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


def profile_sha256(profile: TwinProfile) -> str:
    return hashlib.sha256(profile.to_json().encode("utf-8")).hexdigest()


@lru_cache(maxsize=len(PACKAGED))
def _packaged(name: str) -> TwinProfile:
    res = resources.files("uavcas.twin").joinpath("profiles", PACKAGED[name])
    try:
        return TwinProfile.model_validate_json(res.read_text())
    except (OSError, ValueError) as e:  # a broken installation, not bad user input
        raise ProfileError(f"packaged profile {name!r} unreadable ({str(e).splitlines()[0]})") from None


def default_profile() -> TwinProfile:
    """The calibrated profile shipped with uavcas."""
    return _packaged(DEFAULT_NAME)


def profile_dir() -> Path:
    env = os.environ.get("UAVCAS_PROFILE_DIR")
    return Path(env) if env else Path.home() / ".local" / "share" / "uavcas" / "profiles"


def load_profile(name_or_path: str | os.PathLike | None) -> TwinProfile:
    """None / "default" / "calibrated" -> the shipped calibrated profile; "paper" -> the paper's;
    another name -> the profile directory; a path (ends in .json or holds a separator) -> that file."""
    if name_or_path is None or str(name_or_path) == "default":
        return default_profile()
    text = str(name_or_path)
    if text == "paper":
        return PAPER_PROFILE
    if text in PACKAGED:
        return _packaged(text)
    path = Path(text)
    if not (text.endswith(".json") or os.sep in text):
        if not _NAME.match(text):
            raise ProfileError(f"profile name {text!r} may hold only letters, digits, '.', '_' and '-'")
        path = profile_dir() / f"{text}.json"
    if not path.is_file():
        raise ProfileError(f"profile {text!r} not found (looked for {path}; built in: {', '.join(BUILT_IN)})")
    try:
        return TwinProfile.model_validate_json(path.read_text())
    except ValidationError as e:
        first = e.errors()[0]
        loc = ".".join(str(x) for x in first["loc"])
        raise ProfileError(f"{path}: invalid profile at '{loc}': {first['msg']}") from None
    except (ValueError, OSError) as e:
        raise ProfileError(f"{path}: not a profile JSON ({str(e).splitlines()[0]})") from None


def save_profile(profile: TwinProfile, name_or_path: str | None = None) -> Path:
    """Write a profile under a name (profile directory) or to a path ending in .json."""
    target = name_or_path or profile.name
    if target.endswith(".json") or os.sep in target:
        path = Path(target)
        name = path.stem
    else:
        if not _NAME.match(target):
            raise ProfileError(f"profile name {target!r} may hold only letters, digits, '.', '_' and '-'")
        if target in BUILT_IN:
            raise ProfileError(f"profile name {target!r} is built in; choose another name or give a .json path")
        name, path = target, profile_dir() / f"{target}.json"
    atomic_write_text(path, profile.model_copy(update={"name": name}).to_json())
    return path
