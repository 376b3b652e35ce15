"""`uavcas campaign ...`: manifests (and, with the campaign executor, runs)."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from uavcas.scenario import PRESETS, manifest, parse_shard

from .common import atomic_write_text, console, fail

campaign_app = typer.Typer(help="Campaigns of scenarios: manifests, runs.", no_args_is_help=True)


@campaign_app.command("manifest")
def manifest_cmd(
    out: Path = typer.Option(..., "--out", help="JSONL file to write (one scenario per line)."),
    preset: str = typer.Option("paper", "--preset", help=f"One of: {', '.join(PRESETS)}."),
    seed: int = typer.Option(0, "--seed", help="Seed of the permutation and of the run seeds."),
    shard: str = typer.Option(None, "--shard", help="K/N: keep the K-th of N slices."),
) -> None:
    """Write the campaign's scenarios in seeded-permutation order."""
    if preset not in PRESETS:
        raise fail(f"--preset: unknown preset {preset!r} (known: {', '.join(PRESETS)})")
    try:
        sh = parse_shard(shard) if shard is not None else None
    except ValueError as e:
        raise fail(f"--{e}") from None
    entries = manifest(preset, seed=seed, shard=sh)
    atomic_write_text(out, "".join(json.dumps(e.to_dict(), sort_keys=True) + "\n" for e in entries))
    console.print(f"wrote {len(entries)} scenarios of preset [bold]{preset}[/] to {out}")


def register(app: typer.Typer) -> None:
    app.add_typer(campaign_app, name="campaign")
