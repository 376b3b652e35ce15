"""Helpers shared by the sub-commands: one-line errors with a non-zero exit, atomic writes."""

from __future__ import annotations

import typer
from rich.console import Console
from rich.markup import escape

from uavcas.atomic import atomic_path, atomic_write_bytes, atomic_write_text  # noqa: F401

console = Console()
err_console = Console(stderr=True)
TERMINATION_HELP = ("How a TCP flow ends: connection (default: one connection one flow; closed on RST or the "
                    "acknowledged last FIN, its trailing packets within 60 s join it), cic (CICFlowMeter exactly: "
                    "first backward FIN or RST closes, duplicate forward FIN dropped, no 1-packet flows; reproduces "
                    "its 'TCP appendix' flows) or timeout (nfstream's: idle/active timeouts only).")


def fail(message: str, code: int = 2) -> "typer.Exit":
    """Print a one-line error to stderr and return the Exit to raise.

    The message is plain text: escaped, so brackets in it (a regex, a list) are printed as
    they are instead of being taken for console markup."""
    err_console.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    return typer.Exit(code)


def plan_or_fail(config: str, seed: int, windows: int, window_s: float, profile: str | None):
    """The plan of a scenario, or a one-line error naming the bad field / profile (exit 2)."""
    from uavcas.scenario import ScenarioError
    from uavcas.twin import plan as make_plan
    from uavcas.twin.profile import ProfileError

    try:
        p = make_plan(config, seed=seed, windows=windows, window_s=window_s, profile=profile)
        if p.config != config:
            err_console.print(f"note: scenario normalised to its canonical form {p.config}", highlight=False)
        return p
    except ScenarioError as e:
        raise fail(str(e)) from None
    except ProfileError as e:
        raise fail(f"--profile: {e}") from None
