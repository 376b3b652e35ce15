"""Helpers shared by the sub-commands: one-line errors with a non-zero exit, atomic writes."""

from __future__ import annotations

import typer
from rich.console import Console

from uavcas.atomic import atomic_path, atomic_write_bytes, atomic_write_text  # noqa: F401

console = Console()
err_console = Console(stderr=True)


def fail(message: str, code: int = 2) -> "typer.Exit":
    """Print a one-line error to stderr and return the Exit to raise."""
    err_console.print(f"[bold red]error:[/] {message}", highlight=False, soft_wrap=True)
    return typer.Exit(code)
