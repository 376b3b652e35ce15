"""`uavcas channel predict`: the twin's path-loss models and link chain on a user's geometry;
`uavcas channel models`: the registered models with their standards.

    uavcas channel predict --model M [--profile P] --in GEOM.csv --out OUT.csv [--tx-dbm T]
    uavcas channel models

GEOM.csv has one row per link (or flight-log sample) with columns d3d_m, d2d_m, h_uav_m,
h_bs_m (metres) and optionally fc_ghz (default: the profile's carrier); any other column is
passed through (read, checked, predicted and written by `uavcas.channel.predict`). OUT.csv is
GEOM.csv plus:

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

from pathlib import Path

import typer
from rich.table import Table

from uavcas.channel.pathloss import help_text as pathloss_help
from uavcas.channel.pathloss import names as pathloss_names
from uavcas.channel.pathloss import specs
from uavcas.channel.predict import D2D_TOLERANCE_M, GeometryError, predict_frame, prediction_csv, read_geometry
from uavcas.twin.profile import ProfileError, load_profile

from .common import atomic_write_text, check_output, console, err_console, fail, one_of, profile_option

app = typer.Typer(help="The twin's channel on your own geometry.", no_args_is_help=True)


@app.command("predict")
def predict_cmd(
    model: one_of(pathloss_names()) = typer.Option(
        ..., "--model", help=f"The path-loss model (registry uavcas.channel.pathloss): {pathloss_help()}."),
    geom: Path = typer.Option(..., "--in", help="CSV with d3d_m, d2d_m, h_uav_m, h_bs_m (fc_ghz optional)."),
    out: Path = typer.Option(..., "--out",
                             help="Output CSV: the input plus pathloss_db, snr_db, mcs, rate_mbps, loss."),
    profile: str = profile_option(),
    tx_dbm: float = typer.Option(20.0, "--tx-dbm", help="Transmit power (dBm)."),
    noise_dbm: float = typer.Option(-95.0, "--noise-dbm", help="Noise floor (dBm)."),
) -> None:
    """Evaluate a path-loss model and the link chain on your own geometry."""
    check_output(out, "file")
    try:
        prof = load_profile(profile)
    except ProfileError as e:
        raise fail(f"--profile: {e}") from None
    try:
        df, clamped = read_geometry(geom)
    except GeometryError as e:
        raise fail(f"--in {e}") from None
    if clamped:
        err_console.print(f"note: {clamped} row(s) had d2d_m up to {D2D_TOLERANCE_M:g} m longer than d3d_m "
                          f"(rounding); clamped to d3d_m", highlight=False)
    res = predict_frame(df, model, prof, tx_dbm, noise_dbm)
    atomic_write_text(out, prediction_csv(res))
    console.print(f"{len(res)} rows, model {model}, profile {prof.name}: written to {out}", highlight=False)


@app.command("models")
def models_cmd() -> None:
    """The registered path-loss models: name, standard and version, LOS state, calibration fit."""
    t = Table(title="path-loss models (uavcas.channel.pathloss)", title_justify="left")
    for col in ("name", "model", "standard", "LOS state", "calibration fit"):
        t.add_column(col, overflow="fold")
    for s in specs():
        t.add_row(s.name, s.summary, s.standard, "sampled" if s.samples_los else "-", s.fit or "-")
    console.print(t)


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="channel")
