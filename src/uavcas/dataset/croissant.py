"""The Croissant metadata (MLCommons Croissant 1.1, built and validated by `mlcroissant`) of a
published dataset directory (`uavcas.dataset.publish`).

One FileSet, the Parquet shards (`shards/*.parquet`, each listed with its SHA-256 as a FileObject
of the distribution too, so a reader can check every file it downloads), and one RecordSet over
it, named by the dataset's view (`flows`, or `host_windows` for a window-host dataset): one Field per column of the data
dictionary (`uavcas.dataset.dictionary`), its Croissant data type from the column's Arrow type
(a list column is `isArray`), its description the dictionary's meaning and unit. The card
(`dataset.json`) rides along as a FileObject.

Validation is mlcroissant's own: `mlcroissant.Metadata` checks the graph when it is built, and
the written JSON-LD is read back by `mlcroissant.Dataset`, which checks it again as any user's
loader will; an error raises `CroissantError`, the warnings are returned.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from pathlib import Path

import mlcroissant as mlc
import pyarrow as pa

from uavcas.views import ViewSpec

from .dictionary import columns

CROISSANT_VERSION = "http://mlcommons.org/croissant/1.1"
PARQUET = "application/x-parquet"
SHARDS = "shards"  # the FileSet's id and the folder of the shards


class CroissantError(ValueError):
    """Metadata that mlcroissant refuses; one line."""


@dataclass(frozen=True)
class FileEntry:
    """A file of the published directory: its path relative to it, size and SHA-256."""

    path: str
    size_bytes: int
    sha256: str
    encoding: str


@dataclass(frozen=True)
class DatasetInfo:
    """What Croissant says about the dataset as a whole."""

    name: str
    description: str
    license: str  # an SPDX identifier or a URL
    cite_as: str  # BibTeX of the paper
    version: str  # semantic version of this publication
    url: str | None  # the publication's page, when it has one
    published: dt.datetime
    keywords: tuple[str, ...]


def _data_type(t: pa.DataType):
    """(Croissant data type, is_array) of an Arrow type."""
    if pa.types.is_list(t) or pa.types.is_large_list(t):
        return _data_type(t.value_type)[0], True
    exact = {pa.int8(): mlc.DataType.INT8, pa.int16(): mlc.DataType.INT16, pa.int32(): mlc.DataType.INT32,
             pa.int64(): mlc.DataType.INT64, pa.float32(): mlc.DataType.FLOAT32, pa.float64(): mlc.DataType.FLOAT64,
             pa.bool_(): mlc.DataType.BOOL}
    if t in exact:
        return exact[t], False
    if pa.types.is_string(t) or pa.types.is_large_string(t) or pa.types.is_dictionary(t):
        return mlc.DataType.TEXT, False
    raise CroissantError(f"no Croissant data type for the Arrow type {t}")


def _field_id(record_set: str, name: str) -> str:
    # ids are IRIs: the column names hold spaces and '/' ("Flow Bytes/s"); the name keeps them
    safe = "".join(ch if ch.isalnum() or ch in "_-" else "_" for ch in name)
    return f"{record_set}/{safe}"


def metadata_json(info: DatasetInfo, files: list[FileEntry], schema: pa.Schema, standard: str,
                  view: ViewSpec) -> dict:
    """The Croissant JSON-LD of the published directory; raises CroissantError if mlcroissant
    finds an error while building it."""
    ctx = mlc.Context(conforms_to=CROISSANT_VERSION)
    shards = [f for f in files if f.path.startswith(f"{SHARDS}/")]
    distribution: list = [mlc.FileObject(ctx=ctx, id=f.path, name=f.path, content_url=f.path,
                                         content_size=f"{f.size_bytes} B", encoding_formats=[f.encoding],
                                         sha256=f.sha256) for f in files]
    distribution.append(mlc.FileSet(ctx=ctx, id=SHARDS, name=SHARDS, encoding_formats=[PARQUET],
                                    includes=[f"{SHARDS}/*.parquet"],
                                    description=f"{len(shards)} Parquet shards, one per run; their union is the "
                                                "dataset"))
    rs = view.record_set
    fields = []
    for f, col in zip(schema, columns(schema, standard, view)):
        data_type, is_array = _data_type(f.type)
        fields.append(mlc.Field(
            # a list column: isArray, no arrayShape (Croissant's default, one dimension of any length)
            ctx=ctx, id=_field_id(rs, f.name), name=f.name, data_types=[data_type], is_array=is_array or None,
            description=f"{col.meaning} (unit: {col.unit})",
            source=mlc.Source(ctx=ctx, file_set=SHARDS, extract=mlc.Extract(ctx=ctx, column=f.name))))
    record_set = mlc.RecordSet(ctx=ctx, id=rs, name=rs, fields=fields,
                               description=f"one row = {view.meaning}; the columns of the data dictionary")
    try:
        md = mlc.Metadata(ctx=ctx, name=info.name, description=info.description, license=[info.license],
                          cite_as=info.cite_as, version=info.version, url=info.url,
                          date_published=info.published, keywords=list(info.keywords),
                          distribution=distribution, record_sets=[record_set])
    except mlc.ValidationError as e:
        raise CroissantError(_first_line(e)) from None
    return md.to_json()


def validate(path: Path) -> list[str]:
    """Read the Croissant file at `path` back with mlcroissant (as a user's loader will): its
    warnings, sorted; CroissantError on an error."""
    try:
        ds = mlc.Dataset(jsonld=path)
    except mlc.ValidationError as e:
        raise CroissantError(f"{path}: {_first_line(e)}") from None
    return sorted(ds.metadata.ctx.issues.warnings)


def _first_line(e: Exception) -> str:
    lines = [ln.strip()
             for ln in str(e).splitlines() if ln.strip() and not ln.strip().startswith("Found the following")]
    return lines[0] if lines else type(e).__name__
