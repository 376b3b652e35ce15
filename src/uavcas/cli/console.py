"""The CLI's output streams and its one-line errors: light (rich only), so the root command, which
reports every bad input, loads nothing of the library (`common` re-exports these for the commands)."""

from __future__ import annotations

import typer
from rich.console import Console
from rich.markup import escape


def _console(stderr: bool = False) -> Console:
    # Piped or redirected output is never cut to a terminal's width: rich would otherwise render
    # tables at 80 columns and end cells with an ellipsis ("7.22e-..." in a file).
    c = Console(stderr=stderr)
    return c if c.is_terminal else Console(stderr=stderr, width=100_000)


console = _console()
err_console = _console(stderr=True)


def fail(message: str, code: int = 2) -> "typer.Exit":
    """Print a one-line error to stderr and return the Exit to raise.

    The message is plain text: escaped, so brackets in it (a regex, a list) are printed as
    they are instead of being taken for console markup."""
    err_console.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    return typer.Exit(code)
