"""`uavcas publish DATASET --out DIR`: a dataset directory made into a self-contained publication.

DIR holds:
- `shards/<run>.parquet`: the dataset's Parquet shards, hard-linked when DIR is on the same file
  system (the store replaces a shard by renaming a new file onto it, so a later re-extract never
  changes a published file), else copied. Their union is the dataset; `flows.parquet` (that union,
  rewritten by every extract) is not published twice. `datasets.load_dataset("parquet",
  data_files="DIR/shards/*.parquet")` and `uavcas.load_dataset("DIR/shards/<run>.parquet")` read them;
- `dataset.json`: the dataset's own card, as it is;
- `croissant.json`: MLCommons Croissant 1.1 metadata (`uavcas.dataset.croissant`), validated by
  mlcroissant, with the SHA-256 of every file above;
- `README.md`: the dataset card for people (template `templates/README.md.j2`): class table per
  view, labelling rules (the card's, as the runs were extracted), fidelity, every column with its
  dtype, unit and meaning (the data dictionary), and the licences of the data the twin was
  calibrated on.

DIR is built in a temporary directory beside it and renamed into place once everything is
written and the Croissant file has been read back by mlcroissant (`atomic_dir`): a refusal
leaves nothing.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import shutil
from dataclasses import dataclass
from importlib.metadata import version as installed
from pathlib import Path

import jinja2
import pyarrow.parquet as pq

from uavcas import __version__
from uavcas.atomic import atomic_dir
from uavcas.labels.label import rule_summary
from uavcas.twin.profile import ProfileError, load_profile, profile_sha256
from uavcas.versions import file_sha256
from uavcas.views import card_view

from .croissant import PARQUET, SHARDS, CroissantError, DatasetInfo, FileEntry, metadata_json, validate
from .dictionary import columns, markdown_table
from .runs import class_table, dataset_runs, flagged_lines
from .store import DatasetError, card_standard, read_card

DEFAULT_LICENSE = "CC-BY-4.0"  # SPDX; the data uavcas generates, not the calibration data (CALIBRATION_DATA)
PAPER_URL = "https://github.com/Sripathm2/Collaborative-UAV-Dataset"  # the authors' code and data
PAPER_TITLE = "UAV-CAS: A Calibrated Digital-Twin Dataset for Intrusion Detection in UAV Swarm Networks"
# The paper this system re-implements (../shared/docs/paper-uavcas.tex: authors, repository, DOI).
PAPER_BIBTEX = (
    "@misc{mishra2026uavcas,\n"
    f"  title = {{{PAPER_TITLE}}},\n"
    "  author = {Mishra, Sripath and Bhargava, Bharat and Liu, Zizheng and Islam, Shafkat},\n"
    "  year = {2026},\n"
    f"  howpublished = {{{PAPER_URL}}},\n"
    "  note = {Dataset: https://dx.doi.org/10.21227/zgrg-z865}\n"
    "}"
)
# Where the calibrated profile's data come from and under which terms: the AERPAW measurements as
# re-published by MPACT-Lab (NCSU), ../shared/data/aerpaw/SOURCES.md. Its README states the MIT
# License (no LICENSE file is committed); the measurements themselves are AERPAW's public datasets,
# whose own terms and citations apply.
CALIBRATION_DATA = {
    "name": "AERPAW measurement data (Maeng et al. LTE 3.51 GHz; AFAR flights; AERPAW multi-band channel sounder)",
    "republished_by": "MPACT-Lab (NCSU), https://github.com/MPACT-Lab/uav-spectrum-sensing-insights "
                      "(commit 2e4c305e04e7b96fd4afd31d963b9ae5a5fcd296), with arXiv:2603.10362",
    "license": "MIT, as the re-publication's README states (no LICENSE file is committed there); the data "
               "derive from public AERPAW datasets, whose own terms apply",
    "cite": "the upstream AERPAW datasets (Maeng et al. LTE I/Q dataset; AFAR dataset; AERPAW multi-band "
            "dataset) and arXiv:2603.10362 (Rahman, Maeng, Guvenc, Wong, Sichitiu, Abrahamson, Bhuyan)",
}
_DATA_SETS = {"LTE_dataset": "Maeng et al. LTE 3.51 GHz (path loss)", "AFAR_dataset": "AFAR flights (mobility)",
              "Multi_BW_dataset": "AERPAW multi-band channel sounder"}


class PublishError(DatasetError):
    """A dataset that cannot be published; one line."""


@dataclass(frozen=True)
class Published:
    out: Path
    rows: int
    files: list[FileEntry]
    shards: int
    linked: int  # shards hard-linked (the others were copied)
    warnings: list[str]  # mlcroissant's, on reading croissant.json back
    croissant_version: str  # mlcroissant's version that validated it


def _place(src: Path, dst: Path) -> bool:
    """Hard-link `src` at `dst` (True), or copy it where the file system refuses a link."""
    dst.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.link(src, dst)
        return True
    except OSError:  # another file system, or protected_hardlinks on a file we do not own
        shutil.copy2(src, dst)
        return False


def calibration(card: dict) -> list[dict]:
    """Each twin profile the runs were planned with: its name, SHA-256s, and the data it was fitted
    on (its provenance), when the profile of that name here is the one the card records."""
    out = []
    for name, shas in (card.get("profiles") or {}).items():
        entry = {"name": name, "sha256": shas, "fitted_on": None, "note": ""}
        try:
            prof = load_profile(name)
        except ProfileError:
            entry["note"] = "not found here: what it was fitted on is not recorded in the dataset"
            out.append(entry)
            continue
        if profile_sha256(prof) not in shas:
            entry["note"] = "the profile of this name here differs from the one the runs used"
        elif prof.provenance is None:
            entry["note"] = "built-in numbers (the paper's), fitted on no data here"
        else:
            p = prof.provenance
            counts: dict[str, int] = {}
            for f in p.data_files:
                key = next((v for k, v in _DATA_SETS.items() if k in f.path), f.path.split("/")[0])
                counts[key] = counts.get(key, 0) + 1
            entry["fitted_on"] = {"tool": p.tool, "date": p.fit_date_utc, "seed": p.seed, "files": counts,
                                  "n_files": len(p.data_files)}
        out.append(entry)
    return out


def _origin(card: dict) -> str:
    """Where the rows come from, in words: emulated runs, the synthetic generator or an import."""
    runs = card.get("runs") or []
    if "synthetic" in (card.get("label_modes") or []):
        return "synthetic runs (uavcas dataset synth: flows built packet by packet, no emulation)"
    if any(r.get("source") == "uavcas-csv" for r in runs):
        return "runs imported from the authors' CSV layout (uavcas import)"
    return ("emulated UAV-swarm runs (a calibrated digital twin run on real Linux TCP/IP stacks, attacked, "
            "captured at every switch)")


def _card_text(card: dict, dataset_dir: Path, info: DatasetInfo, files: list[FileEntry], schema) -> str:
    """README.md: the dataset card for people."""
    standard = card_standard(card)
    view = card_view(card)
    names = set(schema.names)
    frame = pq.read_table(dataset_dir / "flows.parquet",
                          columns=[c for c in ("label", "view") if c in names]).to_pandas()
    classes = class_table(frame)
    headlines, parts = rule_summary(card.get("label_rules", []))
    env = jinja2.Environment(loader=jinja2.PackageLoader("uavcas.dataset", "templates"), autoescape=False,
                             undefined=jinja2.StrictUndefined, keep_trailing_newline=True)
    return env.get_template("README.md.j2").render(
        info=info, card=card, rows=int(card.get("n_flows", len(frame))), standard=standard, view=view,
        class_header=list(classes.columns),
        class_rows=classes.to_dict("records"), headlines=headlines, rules=parts,
        fidelity=card.get("fidelity") or {}, flagged=flagged_lines(dataset_runs(dataset_dir, card)),
        column_table="\n".join(markdown_table(columns(schema, standard, view))),
        calibration=calibration(card), calibration_data=CALIBRATION_DATA, files=files, uavcas_version=__version__,
        paper_url=PAPER_URL)


def publish(dataset_dir: str | Path, out: str | Path, name: str | None = None, license: str = DEFAULT_LICENSE,
            version: str = "1.0.0", url: str | None = None) -> Published:
    """Publish DATASET_DIR into OUT (absent or an empty directory); see the module docstring."""

    dataset_dir, out = Path(dataset_dir), Path(out)
    card = read_card(dataset_dir)
    flows = dataset_dir / "flows.parquet"
    shards = sorted((dataset_dir / SHARDS).glob("*.parquet"))
    if not flows.is_file() or not shards:
        raise PublishError(f"{dataset_dir}: no flows.parquet or no {SHARDS}/*.parquet beside dataset.json")
    if out.exists() and any(out.iterdir()):
        raise PublishError(f"{out}: not empty; publish into a new directory")
    schema = pq.read_schema(flows)
    standard = card_standard(card)
    view = card_view(card)
    files = [FileEntry(f"{SHARDS}/{s.name}", s.stat().st_size, file_sha256(s), PARQUET) for s in shards]
    files.append(FileEntry("dataset.json", (dataset_dir / "dataset.json").stat().st_size,
                           file_sha256(dataset_dir / "dataset.json"), "application/json"))
    info = DatasetInfo(
        name=name or dataset_dir.resolve().name,
        description=(f"{card.get('n_flows', 0)} labelled {view.row.plural} of {card.get('n_runs', 0)} {_origin(card)} "
                     f"(features: {standard}; uavcas {__version__}, a re-implementation of: {PAPER_TITLE})."),
        license=license, cite_as=PAPER_BIBTEX, version=version, url=url,
        published=dt.datetime.now(dt.timezone.utc).replace(microsecond=0),
        keywords=("intrusion detection", "UAV swarm", "network flows", "digital twin", "AERPAW"))
    try:
        jsonld = metadata_json(info, files, schema, standard, view)
    except CroissantError as e:
        raise PublishError(f"croissant.json: {e}") from None
    readme = _card_text(card, dataset_dir, info, files, schema)
    linked = 0
    with atomic_dir(out) as tmp:
        for s in shards:
            linked += _place(s, tmp / SHARDS / s.name)
        shutil.copy2(dataset_dir / "dataset.json", tmp / "dataset.json")
        (tmp / "croissant.json").write_text(json.dumps(jsonld, indent=1, ensure_ascii=False) + "\n")
        (tmp / "README.md").write_text(readme)
        try:
            warnings = validate(tmp / "croissant.json")
        except CroissantError as e:
            raise PublishError(str(e).replace(str(tmp), str(out))) from None
    return Published(out, int(card.get("n_flows", 0)), files, len(shards), linked, warnings, installed("mlcroissant"))
