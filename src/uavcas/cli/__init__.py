"""The `uavcas` command. Each sub-command lives in its own module with a `register(app)`."""

from __future__ import annotations

import typer

from uavcas import __version__

from . import campaign as _campaign
from . import plan as _plan

app = typer.Typer(
    name="uavcas",
    help="Calibrated UAV-swarm digital twin -> real Linux stacks -> attacks -> labeled IDS dataset.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

for _module in (_plan, _campaign):
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
    app()
