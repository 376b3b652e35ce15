"""`uavcas calibrate pathloss|mobility|link|fidelity|all --data DIR --out DIR`: fit the twin to
AERPAW measurements and write per layer a JSON, a markdown table and PNG figures."""

from __future__ import annotations

from pathlib import Path

import typer

from uavcas.calibration.loaders import CalibrationDataError
from uavcas.calibration.pipeline import LAYERS, parse_assignment, run
from uavcas.twin.profile import ProfileError

from .common import check_output, console, fail, one_of, seed_option

_LAYERS = ("pathloss", "mobility", "link", "fidelity", "all")


def calibrate_cmd(
    layer: one_of(_LAYERS) = typer.Argument(..., metavar="LAYER", help="What to calibrate."),
    data: Path = typer.Option(..., "--data",
                              help="Folder with the AERPAW data (shared layout or the original downloads)."),
    out: Path = typer.Option(..., "--out", help="Output folder for JSON, markdown and figures."),
    write_profile: str = typer.Option(None, "--write-profile",
                                      help="Save the fitted twin profile (with provenance) under this name, or to a "
                                           "path ending in .json."),
    seed: int = seed_option("Seed of the splits and simulations."),
    missions: str = typer.Option(None, "--missions",
                                 help="AFAR team -> mission, e.g. '301=spiral,328=grid' (default: the paper's)."),
) -> None:
    """Calibrate the digital twin against real AERPAW measurements (paper sec. 4)."""
    if not data.is_dir():
        raise fail(f"--data {data}: not a folder")
    check_output(out, "dir")
    if write_profile is not None and write_profile.endswith(".json"):
        check_output(Path(write_profile), "file", "--write-profile")
    layers = LAYERS if layer == "all" else (layer,)
    try:
        assignment = parse_assignment(missions)
    except ValueError as e:
        raise fail(f"--missions: {e}") from None
    try:
        res = run(layers, data, out, seed=seed, write_profile=write_profile, assignment=assignment,
                  log=lambda m: console.print(m, highlight=False))
    except CalibrationDataError as e:
        raise fail(str(e)) from None
    except ProfileError as e:
        raise fail(f"--write-profile: {e}") from None
    for f in res.files:
        console.print(f"wrote {f}", highlight=False)
    if res.profile_path is not None:
        console.print(f"profile written to {res.profile_path} (use --profile {write_profile})", highlight=False)
    console.print(f"calibrate {layer}: {res.runtime_s:.1f} s")


def register(app: typer.Typer) -> None:
    app.command("calibrate")(calibrate_cmd)
