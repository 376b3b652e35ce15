"""Versions of uavcas, Python and the libraries that shaped an output, recorded beside it
(run.json, dataset.json) so a result can be traced to the code that produced it."""

from __future__ import annotations

import importlib
import sys

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
