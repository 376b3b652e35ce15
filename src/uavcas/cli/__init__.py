"""The `uavcas` command. Each sub-command lives in its own module with a `register(app)`."""

from __future__ import annotations

import errno
from pathlib import Path

import typer

from uavcas import __version__

from . import analyze as _analyze
from . import audit as _audit
from . import calibrate as _calibrate
from . import bench as _bench
from . import campaign as _campaign
from . import channel as _channel
from . import dataset as _dataset
from . import emulate as _emulate
from . import flows as _flows
from . import mavlink as _mavlink
from . import plan as _plan
from . import report as _report
from . import run as _run
from .common import fail

app = typer.Typer(
    name="uavcas",
    help="Calibrated UAV-swarm digital twin -> real Linux stacks -> attacks -> labeled IDS dataset.",
    no_args_is_help=True,
    # -h as well as --help (click hands help_option_names down to every sub-command's context)
    context_settings={"help_option_names": ["-h", "--help"]},
    pretty_exceptions_enable=False,
)

for _module in (_plan, _campaign, _dataset, _flows, _emulate, _analyze, _bench, _report, _run, _calibrate,
                _channel, _audit, _mavlink):
    _module.register(app)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"uavcas {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "-V", "--version", callback=_version, is_eager=True, help="Print the version and exit."),
) -> None:
    """uavcas command line."""


def main() -> None:
    from uavcas.atomic import UnsafeOutput

    try:
        app()
    except UnsafeOutput as exc:  # any command's --out onto a symlink, FIFO, device or directory
        raise SystemExit(fail(str(exc)).exit_code) from None
    except OSError as e:  # a file or folder named on the command line cannot be read or written
        raise SystemExit(_os_error(e).exit_code) from None


_BAD_INPUT_ERRNOS = (errno.EACCES, errno.EPERM, errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.EROFS, errno.EEXIST)


def _os_error(e: OSError) -> typer.Exit:
    """One line naming the path (the target, not the temporary name an atomic write used)."""
    path = Path(e.filename) if e.filename else None
    if path is not None and path.name.startswith(".") and ".tmp" in path.name:
        where = f"cannot write into {path.parent}"
    else:
        where = str(path) if path is not None else "file system"
    return fail(f"{where}: {e.strerror or e}", code=2 if e.errno in _BAD_INPUT_ERRNOS else 1)
