"""The `uavcas` command. Each sub-command lives in its own module with a `register(app)`."""

from __future__ import annotations

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
from . import plan as _plan
from . import report as _report
from . import run as _run

app = typer.Typer(
    name="uavcas",
    help="Calibrated UAV-swarm digital twin -> real Linux stacks -> attacks -> labeled IDS dataset.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

for _module in (_plan, _campaign, _dataset, _flows, _emulate, _analyze, _bench, _report, _run, _calibrate,
                _channel, _audit):
    _module.register(app)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"uavcas {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True),
) -> None:
    """uavcas command line."""


def main() -> None:
    from uavcas.atomic import UnsafeOutput

    try:
        app()
    except UnsafeOutput as exc:  # any command's --out onto a symlink, FIFO, device or directory
        from .common import fail

        raise SystemExit(fail(str(exc)).exit_code) from None
