"""The `uavcas` command. Each top-level command or group lives in the module of its name (`import`
in `import_`, a keyword), parses its arguments and calls the library; each module's `register(app)`
adds its command. `COMMANDS` below, the one place they are registered, gives each one's name, module
and one-line help, in the help's order: the root command lists them from it and imports a command's
module only when that command is resolved (run, or asked for its help), so `uavcas --help` loads no
command's dependencies. Options and checks several commands share are in `common`; the output
streams and one-line errors, which the root needs too, in `console`."""

from __future__ import annotations

import errno
import importlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import typer
import typer.core
import typer.main
from typer._click import Command, Context
from typer._click import exceptions as _click_errors  # typer >= 0.20 carries its own click

from uavcas import __version__
from uavcas.atomic import UnsafeOutput

from .console import fail


@dataclass(frozen=True)
class Registered:
    """A top-level command or group: its name, the module of this package whose `register(app)`
    adds it, and the help line the root's help lists (`tests/test_cli_layout.py` holds it equal
    to the command's own)."""

    name: str
    module: str
    help: str


COMMANDS: tuple[Registered, ...] = (
    Registered("plan", "plan",
               "Plan a scenario: positions, links and their rate/delay/loss per window, attack schedule."),
    Registered("flows", "flows",
               "Flows of one capture (streamed, bounded memory) or of several capture points (de-duplicated)."),
    Registered("extract", "extract",
               "Extract one run into the dataset directory --out (its shard is replaced if it was extracted before)."),
    Registered("export", "export",
               "Export a dataset: in the authors' released layout (one stat and one ts CSV, one row per host\n"
               "pair: 5-tuple flows are merged into host pairs from their packet sequences), or as one plain\n"
               "CSV row per flow for CICIDS2017-style tooling (--format csv)."),
    Registered("import", "import_",
               "Import the authors' CSV layout (theirs as released, or ours) into a dataset directory."),
    Registered("info", "info",
               "Class counts, feature standard, views, fidelity and the runs of a dataset (or its columns)."),
    Registered("doctor", "doctor",
               "Report kernel features, the chosen shaper and tools; measure a two-hop shaped path."),
    Registered("clean", "clean", "Remove what crashed emulation runs left: processes, namespaces (with their links "
                                 "and rules), cgroups."),
    Registered("report", "report", "Write a self-contained HTML report of a dataset: summary, runs, topology, "
                                   "fidelity, distributions, card."),
    Registered("run", "run", "Realise a scenario's plan on real Linux stacks, attack it, capture every switch."),
    Registered("calibrate", "calibrate", "Calibrate the digital twin against real AERPAW measurements (paper sec. 4)."),
    Registered("audit", "audit",
               "Audit a run's timing, loss and rate fidelity against its plan; write fidelity.json."),
    Registered("mavlink", "mavlink",
               "Decode every MAVLink message of a run's captures: one row per message and capture point, with\n"
               "time, addresses, header, fields (JSON and position columns in the message's units), CRC check,\n"
               "a position report's offset from the plan's track (claimed minus true, metres east/north/up: a\n"
               "spoofed GPS's drift) and the packet's effect and family from the ground truth."),
    Registered("publish", "publish",
               "Publish a dataset: its Parquet shards (hard-linked on the same file system, else copied), its\n"
               "card, a Croissant file validated by mlcroissant, and a README dataset card (classes, labelling\n"
               "rules, fidelity, every column with its unit, the calibration data's licence)."),
    Registered("campaign", "campaign", "Campaigns of scenarios: manifests, runs."),
    Registered("dataset", "dataset", "Datasets without an emulation: synthetic flows in the dataset schema."),
    Registered("analyze", "analyze", "Measure a dataset: diversity, per-axis diversity, separability."),
    Registered("bench", "bench", "Benchmarks on a dataset."),
    Registered("channel", "channel", "The twin's channel on your own geometry."),
)


class _Unloaded(typer.core.TyperCommand):
    """What the root holds for a command until it is resolved: its name and help line."""

    def __init__(self, entry: Registered) -> None:
        super().__init__(name=entry.name, help=entry.help)
        self.entry = entry


def _matplotlib_config_dir() -> None:
    """Where matplotlib's config folder cannot be written (a user without a home, e.g. nobody),
    choose a temporary one before a command's module imports matplotlib: matplotlib would use one
    too, but warn on stderr, which holds one line per error here."""
    if "MPLCONFIGDIR" in os.environ:
        return
    own = Path(os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config") / "matplotlib"
    try:
        own.mkdir(parents=True, exist_ok=True)
        writable = os.access(own, os.W_OK)
    except OSError:
        writable = False
    if not writable:
        os.environ["MPLCONFIGDIR"] = tempfile.mkdtemp(prefix="matplotlib-")


def load(entry: Registered) -> Command:
    """The click command or group `entry`'s module registers (its module imported now)."""
    _matplotlib_config_dir()
    module = importlib.import_module(f"{__name__}.{entry.module}")
    holder = typer.Typer()
    module.register(holder)
    return typer.main.get_group(holder).commands[entry.name]


class _OneLineErrors(typer.core.TyperGroup):
    """The root command: every bad input, click's usage errors included, ends in one line on stderr
    and a non-zero exit, whoever invokes it (the console script, `python -m uavcas`, a test's
    CliRunner), instead of click's usage block and typer's framed box. It holds the registered
    commands unloaded and loads one when it is resolved; its own help lists their help lines."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.commands.update((e.name, _Unloaded(e)) for e in COMMANDS)
        self._listing = False

    def list_commands(self, ctx: Context) -> list[str]:
        return [e.name for e in COMMANDS]

    def get_command(self, ctx: Context | None, cmd_name: str) -> Command | None:
        cmd = self.commands.get(cmd_name)
        if isinstance(cmd, _Unloaded) and not self._listing:
            try:
                cmd = self.commands[cmd_name] = load(cmd.entry)
            except ImportError as e:  # a partial installation: one line naming what is missing
                raise fail(f"{cmd_name} cannot load: {e}; reinstall uavcas with its dependencies", 1) from None
        return cmd

    def format_help(self, ctx: Context, formatter) -> None:
        self._listing = True  # the command table needs only the names and help lines
        try:
            super().format_help(ctx, formatter)
        finally:
            self._listing = False

    def main(self, *args, standalone_mode: bool = True, **kwargs):
        try:
            code = super().main(*args, standalone_mode=False, **kwargs)
        except _click_errors.UsageError as exc:
            if type(exc).__name__ == "NoArgsIsHelpError":  # bare `uavcas` / `uavcas campaign`: typer printed the help
                code = 2
            else:
                code = fail(_usage_error(exc)).exit_code
        except typer.Abort:  # end of input at a prompt
            code = fail("interrupted", 130).exit_code
        except UnsafeOutput as exc:  # any command's --out onto a symlink, FIFO, device or directory
            code = fail(str(exc)).exit_code
        except OSError as e:  # a file or folder named on the command line cannot be read or written
            code = _os_error(e).exit_code
        code = code if isinstance(code, int) else 0
        if not standalone_mode:
            return code
        raise SystemExit(code)


app = typer.Typer(
    name="uavcas",
    cls=_OneLineErrors,
    help="Calibrated UAV-swarm digital twin -> real Linux stacks -> attacks -> labeled IDS dataset.",
    no_args_is_help=True,
    # -h as well as --help (click hands help_option_names down to every sub-command's context)
    context_settings={"help_option_names": ["-h", "--help"]},
    pretty_exceptions_enable=False,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"uavcas {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "-V", "--version", callback=_version, is_eager=True,
                                 help="Print the version and exit."),
) -> None:
    """uavcas command line."""


def main() -> None:
    app()


def _usage_error(exc: "_click_errors.UsageError") -> str:
    """`--view: 'bogus' is not one of ...` from click's exception (the command named for context)."""
    msg = exc.format_message()
    if (isinstance(exc, _click_errors.BadParameter) and not isinstance(exc, _click_errors.MissingParameter)
            and exc.param is not None):
        is_argument = getattr(exc.param, "param_type_name", "") == "argument"
        hint = (exc.param.metavar or exc.param.name.upper()) if is_argument else "/".join(exc.param.opts)
        msg = f"{hint}: {exc.message}"
    msg = msg.replace("Value error, ", "")  # typer's pydantic validation prefixes its messages so
    cmd = exc.ctx.command_path if exc.ctx is not None else "uavcas"
    return " ".join(f"{msg} (see {cmd} -h)".split())  # one line, whatever click wrapped


_BAD_INPUT_ERRNOS = (errno.EACCES, errno.EPERM, errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.EROFS, errno.EEXIST)


def _os_error(e: OSError) -> typer.Exit:
    """One line naming the path (the target, not the temporary name an atomic write used)."""
    path = Path(e.filename) if e.filename else None
    if path is not None and path.name.startswith(".") and ".tmp" in path.name:
        where = f"cannot write into {path.parent}"
    else:
        where = str(path) if path is not None else "file system"
    return fail(f"{where}: {e.strerror or e}", code=2 if e.errno in _BAD_INPUT_ERRNOS else 1)
