"""Twin profiles: the calibrated numbers a plan is made with, by name.

A profile bundles the path-loss profile (`channel`), the mobility parameters (`mobility`), the
link-budget settings and the area. `default` is built in (paper numbers, physically anchored
path loss). `uavcas calibrate ... --write-profile NAME` writes `NAME.json` into the profile
directory (`$UAVCAS_PROFILE_DIR`, else `~/.local/share/uavcas/profiles`); `--profile` accepts
such a name or a path to a JSON file.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from uavcas.atomic import atomic_write_text
from uavcas.channel import DEFAULT_PROFILE as DEFAULT_PATHLOSS
from uavcas.channel import LinkLayer, PathLossProfile
from uavcas.mobility import Area, MobilityProfile


class ProfileError(ValueError):
    """A profile that cannot be found or read; one line, names the file."""


class ChannelSettings(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    tx_gain_dbi: float = 0.0
    rx_gain_dbi: float = 0.0
    margin_db: float = 3.0  # adaptive MCS margin above the threshold (paper: 3 dB)
    d_corr_m: float = Field(50.0, gt=0)  # Gudmundson decorrelation distance (paper: 50 m)
    fc_ghz: float = Field(3.51, gt=0)
    link_layer: LinkLayer = LinkLayer()


class TwinProfile(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str = "default"
    source: str = "built in: paper numbers, path loss anchored to free space at 1 m"
    area: Area = Area()
    bs_mast_m: float = Field(25.0, ge=0)  # BSs stand on the ground with a mast (TR 36.777 UMa h_BS)
    pathloss: PathLossProfile = DEFAULT_PATHLOSS
    mobility: MobilityProfile = MobilityProfile()
    channel: ChannelSettings = ChannelSettings()
    backhaul_rate_mbps: float = Field(1000.0, gt=0)  # wired BS interconnect
    backhaul_delay_ms: float = Field(0.5, gt=0)

    def mobility_params(self, mission: str):
        return self.mobility.for_kind(mission)

    def channel_kwargs(self) -> dict:
        c = self.channel
        return {
            "tx_gain_dbi": c.tx_gain_dbi,
            "rx_gain_dbi": c.rx_gain_dbi,
            "margin_db": c.margin_db,
            "d_corr_m": c.d_corr_m,
            "fc_ghz": c.fc_ghz,
            "link_layer": c.link_layer,
        }

    def to_json(self) -> str:
        return self.model_dump_json(indent=1) + "\n"


DEFAULT_PROFILE = TwinProfile()
_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


def profile_dir() -> Path:
    env = os.environ.get("UAVCAS_PROFILE_DIR")
    return Path(env) if env else Path.home() / ".local" / "share" / "uavcas" / "profiles"


def load_profile(name_or_path: str | os.PathLike | None) -> TwinProfile:
    if name_or_path is None or str(name_or_path) == "default":
        return DEFAULT_PROFILE
    text = str(name_or_path)
    path = Path(text)
    if not (text.endswith(".json") or os.sep in text):
        if not _NAME.match(text):
            raise ProfileError(f"profile name {text!r} may hold only letters, digits, '.', '_' and '-'")
        path = profile_dir() / f"{text}.json"
    if not path.is_file():
        raise ProfileError(f"profile {text!r} not found (looked for {path})")
    try:
        return TwinProfile.model_validate_json(path.read_text())
    except ValidationError as e:
        first = e.errors()[0]
        loc = ".".join(str(x) for x in first["loc"])
        raise ProfileError(f"{path}: invalid profile at '{loc}': {first['msg']}") from None
    except ValueError as e:
        raise ProfileError(f"{path}: not a profile JSON ({str(e).splitlines()[0]})") from None


def save_profile(profile: TwinProfile, name: str | None = None) -> Path:
    name = name or profile.name
    if not _NAME.match(name):
        raise ProfileError(f"profile name {name!r} may hold only letters, digits, '.', '_' and '-'")
    path = profile_dir() / f"{name}.json"
    atomic_write_text(path, profile.model_copy(update={"name": name}).to_json())
    return path
