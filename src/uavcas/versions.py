"""Versions of uavcas, Python and the libraries that shaped an output, recorded beside it
(run.json, dataset.json) so a result can be traced to the code that produced it; and the SHA-256
of a file (the data a profile was fitted on, the files of a publication)."""

from __future__ import annotations

import hashlib
import importlib
import sys
from pathlib import Path

from uavcas import __version__


def package_versions(*modules: str) -> dict[str, str | None]:
    """{'uavcas': ..., 'python': ..., module: version or None when it is not installed}."""
    out: dict[str, str | None] = {"uavcas": __version__, "python": sys.version.split()[0]}
    for name in modules:
        try:
            out[name] = getattr(importlib.import_module(name), "__version__", None)
        except ImportError:
            out[name] = None
    return out


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file's bytes (hex), read 1 MiB at a time."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
