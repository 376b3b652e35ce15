"""`uavcas plan CONFIG`: the pure digital-twin plan of one scenario."""

from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    pass
