"""`uavcas channel predict`: the twin's path-loss models and link chain on a user's geometry;
`uavcas channel models`: the registered models with their standards.

    uavcas channel predict --model M [--profile P] --in GEOM.csv --out OUT.csv [--tx-dbm T]
    uavcas channel models

GEOM.csv has one row per link (or flight-log sample) with columns d3d_m, d2d_m, h_uav_m,
h_bs_m (metres) and optionally fc_ghz (default: the profile's carrier); any other column is
passed through. OUT.csv is GEOM.csv plus:

* pathloss_db - the model's median loss (`PathLossModel.loss_db`): no shadowing, no fading; for
  a model with a LOS state the LOS-probability-weighted mean P PL_LOS + (1 - P) PL_NLOS;
  log-distance with the profile's n(h), PL0 and carrier anchor. The models are those of the
  registry `uavcas.channel.pathloss` (`--help` lists them).
* snr_db = tx_dbm + antenna gains (profile) - pathloss_db - noise_dbm.
* mcs, rate_mbps, loss - the link chain of the plan for one link alone on the channel
  (`uavcas.channel.linkchain.predict_links`, the `LinkChain` the twin's `Channel` runs: coded
  PER, Rician fading with the profile's K(h) at h_uav_m averaged over a window, retry chain, the
  profile's MCS selection). rate_mbps is the single-link DCF rate; in a plan, links in
  carrier-sense range share it (`LinkChain.shared_rate_mbps`).
"""

from __future__ import annotations

import io
from pathlib import Path

import typer

from uavcas.channel.pathloss import help_text as pathloss_help
from uavcas.channel.pathloss import names as pathloss_names

from .common import atomic_write_text, check_output, console, err_console, fail, one_of, profile_option

REQUIRED = ("d3d_m", "d2d_m", "h_uav_m", "h_bs_m")
# A 2-D distance longer than the 3-D one is impossible, but rounded coordinates give it by a little
# (positions to the metre: up to ~0.5 m); within this, d2d_m is clamped to d3d_m and the rows counted.
D2D_TOLERANCE_M = 0.5
OUTPUT = ("pathloss_db", "snr_db", "mcs", "rate_mbps", "loss")

app = typer.Typer(help="The twin's channel on your own geometry.", no_args_is_help=True)


def _read_geometry(path: Path):
    import numpy as np
    import pandas as pd

    if not path.is_file():
        raise fail(f"--in {path}: no such file")
    try:
        df = pd.read_csv(path)
    except Exception as e:  # pandas raises several types on garbage
        raise fail(f"--in {path}: not a readable CSV ({str(e).splitlines()[0] if str(e) else type(e).__name__})") from None
    missing = [c for c in REQUIRED if c not in df.columns]
    if missing:
        raise fail(f"--in {path}: missing column(s) {', '.join(missing)} (need {', '.join(REQUIRED)}; fc_ghz optional)")
    if df.empty:
        raise fail(f"--in {path}: no rows")
    clash = [c for c in OUTPUT if c in df.columns]
    if clash:
        raise fail(f"--in {path}: already has output column(s) {', '.join(clash)}")
    for c in REQUIRED + (("fc_ghz",) if "fc_ghz" in df.columns else ()):
        v = pd.to_numeric(df[c], errors="coerce")
        bad = ~np.isfinite(v.to_numpy(dtype=float))
        if bad.any():
            raise fail(f"--in {path}: column {c} row {int(np.flatnonzero(bad)[0]) + 1}: not a finite number ({df[c].iloc[int(np.flatnonzero(bad)[0])]!r})")
        df[c] = v.astype(float)
    for c in ("d3d_m", "d2d_m", "h_uav_m", "h_bs_m"):
        neg = df[c] < 0
        if neg.any():
            raise fail(f"--in {path}: column {c} row {int(neg.idxmax()) + 1}: negative ({df[c][neg.idxmax()]})")
    if "fc_ghz" in df.columns and (df["fc_ghz"] <= 0).any():
        raise fail(f"--in {path}: column fc_ghz row {int((df['fc_ghz'] <= 0).idxmax()) + 1}: must be > 0")
    excess = df["d2d_m"] - df["d3d_m"]
    impossible = excess > D2D_TOLERANCE_M
    if impossible.any():
        row = int(impossible.idxmax())
        raise fail(f"--in {path}: row {row + 1}: d2d_m {df['d2d_m'][row]:g} exceeds d3d_m {df['d3d_m'][row]:g} by more "
                   f"than {D2D_TOLERANCE_M:g} m")
    clamp = excess > 0
    if clamp.any():
        df.loc[clamp, "d2d_m"] = df.loc[clamp, "d3d_m"]
        err_console.print(f"note: {int(clamp.sum())} row(s) had d2d_m up to {D2D_TOLERANCE_M:g} m longer than d3d_m "
                          f"(rounding); clamped to d3d_m", highlight=False)
    return df


def predict_frame(df, model_name: str, profile, tx_dbm: float, noise_dbm: float):
    """The output columns for a validated geometry frame (see module docstring)."""
    import numpy as np

    from uavcas.channel import LinkChain, LinkGeometry, predict_links

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


@app.command("predict")
def predict_cmd(
    model: one_of(pathloss_names()) = typer.Option(
        ..., "--model", help=f"The path-loss model (registry uavcas.channel.pathloss): {pathloss_help()}."),
    geom: Path = typer.Option(..., "--in", help="CSV with d3d_m, d2d_m, h_uav_m, h_bs_m (fc_ghz optional)."),
    out: Path = typer.Option(..., "--out", help="Output CSV: the input plus pathloss_db, snr_db, mcs, rate_mbps, loss."),
    profile: str = profile_option(),
    tx_dbm: float = typer.Option(20.0, "--tx-dbm", help="Transmit power (dBm)."),
    noise_dbm: float = typer.Option(-95.0, "--noise-dbm", help="Noise floor (dBm)."),
) -> None:
    """Evaluate a path-loss model and the link chain on your own geometry."""
    from uavcas.twin.profile import ProfileError, load_profile

    check_output(out, "file")
    try:
        prof = load_profile(profile)
    except ProfileError as e:
        raise fail(f"--profile: {e}") from None
    df = _read_geometry(geom)
    res = predict_frame(df, model, prof, tx_dbm, noise_dbm)
    buf = io.StringIO()
    res.to_csv(buf, index=False, float_format="%.10g")
    atomic_write_text(out, buf.getvalue())
    console.print(f"{len(res)} rows, model {model}, profile {prof.name}: written to {out}", highlight=False)


@app.command("models")
def models_cmd() -> None:
    """The registered path-loss models: name, standard and version, LOS state, calibration fit."""
    from rich.table import Table

    from uavcas.channel.pathloss import specs

    t = Table(title="path-loss models (uavcas.channel.pathloss)", title_justify="left")
    for col in ("name", "model", "standard", "LOS state", "calibration fit"):
        t.add_column(col, overflow="fold")
    for s in specs():
        t.add_row(s.name, s.summary, s.standard, "sampled" if s.samples_los else "-", s.fit or "-")
    console.print(t)


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="channel")
