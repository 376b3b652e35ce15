"""Helpers shared by the sub-commands: one-line errors with a non-zero exit, atomic writes, the
options and arguments several commands take (one name, one bound, one help each), and the check
every output gets before any work starts."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Literal

import typer
from rich.markup import escape

from uavcas.atomic import UnsafeOutput, atomic_path, atomic_write_bytes, atomic_write_text, check_out_dir, check_target  # noqa: F401
from uavcas.dataset.external import ExternalFormatError
from uavcas.dataset.store import DatasetError
from uavcas.dataset.uavcas_csv import CsvFormatError
from uavcas.flows import CaptureError
from uavcas.flows.assemble import VIEWS
from uavcas.flows.standards import DEFAULT_STANDARD, names, standards
from uavcas.flows.termination import TERMINATIONS
from uavcas.labels import LabelError
from uavcas.network.naming import check_prefix as check
from uavcas.scenario import ScenarioError
from uavcas.twin.plan import plan as make_plan
from uavcas.twin.profile import ProfileError
from uavcas.twin.schedule import RoundError
from uavcas.views import views as registered_views

from .console import console, err_console, fail  # noqa: F401  (the commands take them from here)

TERMINATION_HELP = ("How a TCP flow ends: connection (default: one connection one flow; closed on RST or the "
                    "acknowledged last FIN, its trailing packets within 60 s join it), cic (CICFlowMeter exactly: "
                    "first backward FIN or RST closes, duplicate forward FIN dropped, no 1-packet flows; reproduces "
                    "its 'TCP appendix' flows) or timeout (nfstream's: idle/active timeouts only).")

VIEW_HELP = "What each run is extracted to: " + "; ".join(f"{v.name} ({v.help})" for v in registered_views()) + "."
FEATURES_HELP = "Feature standard: " + "; ".join(f"{s.name} ({s.summary})" for s in standards()) + "."

# --- choices, arguments and options shared by several commands ------------------------------------
MIN_WINDOW_S = 0.5  # a plan is made to be run: the emulation's shortest window (the same for plan and run)


def one_of(values) -> Any:
    """The annotation of an option taking one of these words: typer lists them in the help,
    completes them, and refuses any other in one line."""
    return Literal[tuple(values)]


View = one_of(VIEWS)  # a flow view of `uavcas.flows.assemble`
ExtractView = one_of(v.name for v in registered_views())  # a view of the registry `uavcas.views`
Standard = one_of(names())  # a feature standard of the registry `uavcas.flows.standards`
Termination = one_of(TERMINATIONS)


def config_argument() -> Any:
    return typer.Argument(..., metavar="CONFIG",
                          help="Scenario string, e.g. dos=1000-5-2-image-logdist-adaptive-random-30-95")


def dataset_argument(help: str = "Dataset directory (flows.parquet + dataset.json).") -> Any:
    return typer.Argument(..., metavar="DATASET", help=help)


def run_dir_argument(help: str = "Run directory (plan.json, run.json, attacks.jsonl, pcap/).") -> Any:
    return typer.Argument(..., metavar="RUN_DIR", help=help)


def seed_option(help: str = "Seed: the same seed and config give the same result.") -> Any:
    return typer.Option(0, "--seed", min=0, help=help)


def windows_option() -> Any:
    return typer.Option(12, "--windows", min=1, help="Number of plan windows.")


def window_s_option() -> Any:
    return typer.Option(5.0, "--window-s", min=MIN_WINDOW_S, help="Window length in seconds.")


def rounds_option() -> Any:
    return typer.Option(1, "--rounds", "--episodes", min=1,
                        help="Attack rounds per run: the composition again on fresh victims, 10-20 s each, >= 5 s "
                             "apart (the medium preset uses 3). --episodes: its old name, deprecated.")


def profile_option() -> Any:
    return typer.Option(None, "--profile", help="Twin profile (channel and mobility): a name or a JSON path "
                                                "(default: the calibrated one).")


def features_option() -> Any:
    return typer.Option(DEFAULT_STANDARD, "--features", help=FEATURES_HELP)


def view_option() -> Any:
    return typer.Option("5tuple", "--view", help=VIEW_HELP)


def termination_option() -> Any:
    return typer.Option(None, "--termination", help=TERMINATION_HELP)


def allow_truncated_option() -> Any:
    return typer.Option(False, "--allow-truncated", help="Keep the packets before a truncation.")


def min_attack_fraction_option() -> Any:
    return typer.Option(0.0, "--min-attack-fraction", min=0.0, max=1.0,
                        help="Leave out flows whose share of attack packets is above 0 but below this "
                             "(default 0: keep all).")


def prefix_option(help: str) -> Any:
    return typer.Option(None, "--prefix", help=help)


def prefix_or_fail(prefix: str | None) -> str | None:
    """A `--prefix` the emulation can use (`uavcas.network.naming`), or a one-line error (exit 2)."""
    if prefix is not None:
        try:
            check(prefix)
        except ValueError as e:
            raise fail(f"--prefix: {e}") from None
    return prefix


def check_output(path: Path, kind: Literal["file", "dir"], option: str = "--out") -> Path:
    """Check an output the user named before any work starts (a one-line error, exit 2, if bad).

    A file must be absent or a regular file, a directory absent or a directory (`uavcas.atomic`'s
    rules). A file's folder must exist: uavcas creates no folder the user did not name (`plan --out
    /no/such/dir/plan.json` is refused). An output directory is named as one: it is created, like
    `mkdir -p`, with any missing parents, once the command has work to write."""
    try:
        (check_target if kind == "file" else check_out_dir)(path)
    except UnsafeOutput as e:
        raise fail(f"{option}: {e}") from None
    parent = path.parent if str(path.parent) else Path(".")
    if kind == "file" and not os.path.lexists(path) and not parent.is_dir():
        raise fail(f"{option} {path}: its folder {parent} does not exist (create it first)")
    return path


def dataset_errors() -> tuple[type[Exception], ...]:
    """What reading captures, runs and datasets raises on bad input: each is a one-line error."""
    return (CaptureError, DatasetError, LabelError, CsvFormatError, ExternalFormatError, ValueError, OSError)


def warn(lines) -> None:
    """Each line as a warning on stderr, as plain text like `fail`'s (a path or a list in brackets
    is printed as it is, not taken for console markup)."""
    for line in lines:
        err_console.print(f"[yellow]warning:[/] {escape(str(line))}", highlight=False, soft_wrap=True)


def path_fail(path: Path, error: Exception) -> "typer.Exit":
    """A one-line error about an input path, naming it once (the library's message may already)."""
    msg = str(error).splitlines()[0] if str(error) else type(error).__name__
    return fail(msg if str(path) in msg else f"{path}: {msg}")


def plan_or_fail(config: str, seed: int, windows: int, window_s: float, profile: str | None, rounds: int = 1,
                 **kw):
    """The plan of a scenario, or a one-line error naming the bad field / profile (exit 2).
    `kw`: more of `twin.plan.plan`'s arguments (`stream_hz`)."""
    try:
        p = make_plan(config, seed=seed, windows=windows, window_s=window_s, profile=profile, rounds=rounds, **kw)
        if p.config != config:
            err_console.print(f"note: scenario normalised to its canonical form {p.config}", highlight=False)
        return p
    except (ScenarioError, RoundError) as e:
        raise fail(str(e)) from None
    except ProfileError as e:
        raise fail(f"--profile: {e}") from None
