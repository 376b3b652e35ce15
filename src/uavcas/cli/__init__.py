"""The `uavcas` command. Each top-level command or group lives in the module of its name (`import`
in `import_`, a keyword), parses its arguments and calls the library; each module's `register(app)`
adds its command, and the tuple below, the one place they are registered, gives their order in the
help. Options and checks several commands share are in `common`."""

from __future__ import annotations

import errno
from pathlib import Path

import typer
import typer.core
from typer._click import exceptions as _click_errors  # typer >= 0.20 carries its own click

from uavcas import __version__

from . import analyze as _analyze
from . import audit as _audit
from . import bench as _bench
from . import calibrate as _calibrate
from . import campaign as _campaign
from . import channel as _channel
from . import clean as _clean
from . import dataset as _dataset
from . import doctor as _doctor
from . import export as _export
from . import extract as _extract
from . import flows as _flows
from . import import_ as _import
from . import info as _info
from . import mavlink as _mavlink
from . import plan as _plan
from . import publish as _publish
from . import report as _report
from . import run as _run
from .common import fail


class _OneLineErrors(typer.core.TyperGroup):
    """The root command: every bad input, click's usage errors included, ends in one line on stderr
    and a non-zero exit, whoever invokes it (the console script, `python -m uavcas`, a test's
    CliRunner), instead of click's usage block and typer's framed box."""

    def main(self, *args, standalone_mode: bool = True, **kwargs):
        from uavcas.atomic import UnsafeOutput

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

for _module in (_plan, _campaign, _dataset, _flows, _extract, _export, _import, _info, _doctor, _clean, _analyze,
                _bench, _report, _run, _calibrate, _channel, _audit, _mavlink, _publish):
    _module.register(app)


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
