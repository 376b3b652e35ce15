"""On-disk layout of a campaign inside its dataset directory, and what "done" means.

    DATASET_DIR/campaign.jsonl        the manifest being worked on (written once, then checked)
    DATASET_DIR/campaign_extraction.json  the view, termination policy (and a feature standard other than
                                      the default) runs are extracted with (likewise)
    DATASET_DIR/campaign_emulation.json   the run options runs are emulated with: MAVLink signing (likewise)
    DATASET_DIR/runs/<index>/         one run: plan.json, run.json, attacks.jsonl, shaping.jsonl,
                                      pcap/ (local runs), outcome.json
    DATASET_DIR/runs/<index>/DONE     written last, by rename: the run and its shard are complete
    DATASET_DIR/shards/<index>.parquet the run's flows (see uavcas.dataset.store)
    DATASET_DIR/flows.parquet, dataset.json   rebuilt from the shards of DONE runs only

A run without DONE is unfinished, whatever else it left: on resume its directory and shard are
deleted and it is done again, so a killed campaign never leaves duplicate or partial rows.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from uavcas.atomic import atomic_write_text
from uavcas.dataset.parquet import table_meta
from uavcas.flows.standards import DEFAULT_STANDARD
from uavcas.scenario import ManifestEntry, parse

if TYPE_CHECKING:
    from .task import Extraction


class CampaignError(ValueError):
    """A campaign that cannot proceed; one-line message."""


@dataclass(frozen=True)
class CampaignDir:
    root: Path

    @property
    def manifest_path(self) -> Path:
        return self.root / "campaign.jsonl"

    @property
    def extraction_path(self) -> Path:
        return self.root / "campaign_extraction.json"

    def bind_extraction(self, extraction: "Extraction") -> None:
        """Record how runs are extracted (view and termination policy); resuming with another is
        refused (its shards would mix two descriptions of the traffic, or flows with episodes). A
        campaign begun before this was recorded is checked against its DONE shards."""
        # the feature standard is recorded when not the default (files written before it was recorded: the default)
        std = {} if extraction.features == DEFAULT_STANDARD else {"features": extraction.features}
        want = {"view": extraction.view, "termination": extraction.policy, **std}
        if self.extraction_path.exists():
            have = [json.loads(self.extraction_path.read_text())]
        else:
            metas = [table_meta(s) for s in sorted((self.root / "shards").glob("*.parquet"))
                     if s.stem.isdigit() and self.is_done(int(s.stem))]
            # shards from before the termination policies record none (their flows were cut at
            # the first backward FIN): they differ from any policy of today
            have = [{"view": m.get("view", "5tuple"), "termination": (m.get("flow_rules") or {}).get("termination"),
                     **({"features": m["features"]} if m.get("features", DEFAULT_STANDARD) != DEFAULT_STANDARD else {})}
                    for m in metas]
        for h in have:
            if h != want:
                raise CampaignError(
                    f"{self.root} holds a campaign extracted with {_options(h)}, not {_options(want)}; resume it with "
                    "those or use another --out")
        if not self.extraction_path.exists():
            atomic_write_text(self.extraction_path, json.dumps(want) + "\n")

    @property
    def emulation_path(self) -> Path:
        return self.root / "campaign_emulation.json"

    def bind_emulation(self, mavlink_signing: bool) -> None:
        """Record the run options every run of the campaign is emulated with (MAVLink signing);
        resuming with others is refused, so one campaign's runs are all defended or all not. A
        campaign begun before this was recorded had no signing."""
        want = {"mavlink_signing": bool(mavlink_signing)}
        if self.emulation_path.exists():
            have = json.loads(self.emulation_path.read_text())
        elif any(s.stem.isdigit() and self.is_done(int(s.stem)) for s in (self.root / "shards").glob("*.parquet")):
            have = {"mavlink_signing": False}
        else:
            have = want
        if have != want:
            flag = "--mavlink-signing" if have["mavlink_signing"] else "--no-mavlink-signing"
            raise CampaignError(f"{self.root} holds a campaign emulated with {flag}; resume it with that or use "
                                "another --out")
        if not self.emulation_path.exists():
            atomic_write_text(self.emulation_path, json.dumps(want) + "\n")

    def run_dir(self, index: int) -> Path:
        return self.root / "runs" / str(index)

    def shard_path(self, index: int) -> Path:
        return self.root / "shards" / f"{index}.parquet"

    def is_done(self, index: int) -> bool:
        return (self.run_dir(index) / "DONE").is_file()

    def mark_done(self, index: int, summary: dict) -> None:
        atomic_write_text(self.run_dir(index) / "DONE", json.dumps(summary, sort_keys=True) + "\n")

    def reset(self, index: int) -> None:
        """Forget an unfinished run: its directory and its shard."""
        shutil.rmtree(self.run_dir(index), ignore_errors=True)
        self.shard_path(index).unlink(missing_ok=True)

    def prune_orphan_shards(self) -> list[Path]:
        """Shards whose run is not DONE (killed between shard and marker) are removed."""
        removed = []
        for shard in sorted((self.root / "shards").glob("*.parquet")):
            stem = shard.stem
            if not (stem.isdigit() and self.is_done(int(stem))):
                shard.unlink()
                removed.append(shard)
        return removed

    def bind_manifest(self, entries: list[ManifestEntry]) -> None:
        """Record the manifest; a different manifest in the same directory is refused.

        Resuming relies on index -> (config, seed) being the same as the first time.
        """
        text = manifest_text(entries)
        if self.manifest_path.exists():
            old = {json.loads(line)["index"]: json.loads(line)
                   for line in self.manifest_path.read_text().splitlines() if line}
            for e in entries:
                prev = old.get(e.index)
                if prev is not None and prev != e.to_dict():
                    raise CampaignError(
                        f"{self.root} already holds a campaign whose run {e.index} is "
                        f"{prev['config']} seed {prev['seed']}, not {e.config} seed {e.seed}; use another --out"
                    )
            merged = {**old, **{e.index: e.to_dict() for e in entries}}
            text = "".join(json.dumps(merged[k], sort_keys=True) + "\n" for k in sorted(merged))
        atomic_write_text(self.manifest_path, text)


def manifest_text(entries: list[ManifestEntry]) -> str:
    """A manifest's JSONL: one entry per line, keys sorted (what `read_manifest` reads)."""
    return "".join(json.dumps(e.to_dict(), sort_keys=True) + "\n" for e in entries)


def write_manifest(path: Path, entries: list[ManifestEntry]) -> Path:
    """Write a manifest file (atomically): `uavcas campaign manifest`."""
    return atomic_write_text(path, manifest_text(entries))


def read_manifest(path: Path) -> list[ManifestEntry]:
    """A manifest file written by `uavcas campaign manifest` (or by hand, same fields)."""
    entries = []
    try:
        lines = Path(path).read_text().splitlines()
    except OSError as e:
        raise CampaignError(f"{path}: cannot read manifest ({e.strerror})") from None
    for no, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            d = json.loads(line)
            parse(d["config"])
            entries.append(
                ManifestEntry(
                    index=int(d["index"]),
                    position=int(d.get("position", no - 1)),
                    config=d["config"],
                    seed=int(d["seed"]),
                    windows=int(d.get("windows", 12)),
                    window_s=float(d.get("window_s", 5.0)),
                    rounds=int(d.get("episodes", 1)),  # the stored key keeps its old name (ManifestEntry.to_dict)
                )
            )
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as e:
            msg = str(e).splitlines()[0] if str(e) else type(e).__name__
            raise CampaignError(f"{path}:{no}: bad manifest line ({msg})") from None
    if len({e.index for e in entries}) != len(entries):
        raise CampaignError(f"{path}: duplicate index in manifest")
    if not entries:
        raise CampaignError(f"{path}: empty manifest")
    return entries


def _options(recorded: dict) -> str:
    """A recorded extraction as the options that give it."""
    std = recorded.get("features")
    return f"--view {recorded['view']} --termination {recorded['termination']}" + (f" --features {std}" if std else "")
