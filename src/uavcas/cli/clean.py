"""`uavcas clean`: remove what crashed emulation runs left (`uavcas.emulation.cleanup`)."""

from __future__ import annotations

import os

import typer

from uavcas.emulation.cleanup import clean as do_clean

from .common import console, fail, prefix_option, prefix_or_fail


def clean(
    prefix: str = prefix_option("Only this run's prefix (default: every dead registered run)."),
    force: bool = typer.Option(False, "--force", help="Also clean a run that is still alive."),
) -> None:
    """Remove what crashed emulation runs left: processes, namespaces (with their links and rules), cgroups."""
    if os.geteuid() != 0:
        raise fail("clean needs root")
    prefix_or_fail(prefix)
    reports = do_clean(prefix, force=force)
    if not reports:
        console.print("nothing to clean")
    for r in reports:
        if r.skipped_live:
            console.print(f"{r.prefix}: live run, skipped (use --force)")
        elif r.error is None:
            console.print(f"{r.prefix}: removed {len(r.namespaces)} namespaces, killed {len(r.killed_pids)} "
                          f"processes, removed {len(r.cgroups)} cgroups")
    failed = [r for r in reports if r.error is not None]
    if failed:
        raise fail("; ".join(f"{r.prefix}: {r.error}" for r in failed) + " (run `uavcas clean` again)", code=1)


def register(app: typer.Typer) -> None:
    app.command("clean")(clean)
