"""The link chain on a user's geometry table (what `uavcas channel predict` reads and writes).

GEOM.csv has one row per link (or flight-log sample) with columns d3d_m, d2d_m, h_uav_m, h_bs_m
(metres) and optionally fc_ghz (default: the profile's carrier); any other column is passed
through. `read_geometry` checks it (a `GeometryError` of one line naming the row and column),
`predict_frame` adds `OUTPUT` (`linkchain.predict_links`: the model's median loss, the SNR, the
link chain's MCS, rate and loss), `prediction_csv` is the text of the output file (the package
imports nothing of uavcas: the caller writes the text, atomically).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .geometry import LinkGeometry
from .linkchain import LinkChain, predict_links

REQUIRED = ("d3d_m", "d2d_m", "h_uav_m", "h_bs_m")
# A 2-D distance longer than the 3-D one is impossible, but rounded coordinates give it by a little
# (positions to the metre: up to ~0.5 m); within this, d2d_m is clamped to d3d_m and the rows counted.
D2D_TOLERANCE_M = 0.5
OUTPUT = ("pathloss_db", "snr_db", "mcs", "rate_mbps", "loss")


class GeometryError(ValueError):
    """A geometry table that cannot be predicted; one line starting with the file's path."""


def read_geometry(path: Path) -> tuple[pd.DataFrame, int]:
    """The checked geometry table of `path` (numeric columns as float) and how many rows had
    d2d_m clamped to d3d_m (`D2D_TOLERANCE_M`)."""
    path = Path(path)
    if not path.is_file():
        raise GeometryError(f"{path}: no such file")
    try:
        df = pd.read_csv(path)
    except Exception as e:  # pandas raises several types on garbage
        why = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise GeometryError(f"{path}: not a readable CSV ({why})") from None
    missing = [c for c in REQUIRED if c not in df.columns]
    if missing:
        raise GeometryError(f"{path}: missing column(s) {', '.join(missing)} "
                            f"(need {', '.join(REQUIRED)}; fc_ghz optional)")
    if df.empty:
        raise GeometryError(f"{path}: no rows")
    clash = [c for c in OUTPUT if c in df.columns]
    if clash:
        raise GeometryError(f"{path}: already has output column(s) {', '.join(clash)}")
    for c in REQUIRED + (("fc_ghz",) if "fc_ghz" in df.columns else ()):
        v = pd.to_numeric(df[c], errors="coerce")
        bad = ~np.isfinite(v.to_numpy(dtype=float))
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise GeometryError(f"{path}: column {c} row {row + 1}: not a finite number ({df[c].iloc[row]!r})")
        df[c] = v.astype(float)
    for c in REQUIRED:
        neg = df[c] < 0
        if neg.any():
            raise GeometryError(f"{path}: column {c} row {int(neg.idxmax()) + 1}: negative ({df[c][neg.idxmax()]})")
    if "fc_ghz" in df.columns and (df["fc_ghz"] <= 0).any():
        raise GeometryError(f"{path}: column fc_ghz row {int((df['fc_ghz'] <= 0).idxmax()) + 1}: must be > 0")
    excess = df["d2d_m"] - df["d3d_m"]
    impossible = excess > D2D_TOLERANCE_M
    if impossible.any():
        row = int(impossible.idxmax())
        raise GeometryError(f"{path}: row {row + 1}: d2d_m {df['d2d_m'][row]:g} exceeds d3d_m {df['d3d_m'][row]:g} "
                            f"by more than {D2D_TOLERANCE_M:g} m")
    clamp = excess > 0
    df.loc[clamp, "d2d_m"] = df.loc[clamp, "d3d_m"]
    return df, int(clamp.sum())


def predict_frame(df: pd.DataFrame, model_name: str, profile, tx_dbm: float, noise_dbm: float) -> pd.DataFrame:
    """`df` (checked by `read_geometry`) plus the `OUTPUT` columns, for path-loss model
    `model_name` and a twin profile (`uavcas.twin.profile.TwinProfile`: its path-loss parameters,
    carrier and chain settings)."""
    fc = df["fc_ghz"].to_numpy(float) if "fc_ghz" in df.columns else np.full(len(df), profile.channel.fc_ghz)
    geom = LinkGeometry(d3d_m=df["d3d_m"].to_numpy(float), d2d_m=df["d2d_m"].to_numpy(float),
                        h_ground_m=df["h_bs_m"].to_numpy(float), h_air_m=df["h_uav_m"].to_numpy(float),
                        air_to_air=np.zeros(len(df), dtype=bool))
    chain = LinkChain.build(tx_power_dbm=tx_dbm, noise_dbm=noise_dbm, **profile.chain_kwargs())
    res = predict_links(model_name, profile.pathloss, fc, geom, chain)
    out = df.copy()
    for col in OUTPUT:
        out[col] = getattr(res, col)
    return out


def prediction_csv(frame: pd.DataFrame) -> str:
    """The frame as CSV text, floats to 10 significant digits (well below any model's error)."""
    return frame.to_csv(index=False, float_format="%.10g")
