"""The one place matplotlib is set up: no display (Agg), PNGs written atomically.

Modules that draw import `plt` from here, so the backend is chosen before any figure exists
(headless machines, CI and the campaign workers have no display to open). A leaf: it imports
nothing of uavcas but `atomic` (itself a leaf, the one home of file output), so the report, the
IDS benchmark, analysis and calibration all draw through it without importing each other.
"""

from __future__ import annotations

import base64
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from uavcas.atomic import atomic_path  # noqa: E402

__all__ = ["plt", "png_data_uri", "save_png"]


def save_png(fig, path: str | Path, dpi: float | str = 120, tight: bool = True) -> Path:
    """Write `fig` to `path` (readers never see half a PNG) and close it, also when saving fails.

    `dpi="figure"` keeps the figure's own resolution; `tight=False` keeps its full canvas
    (fixed-size panels that must line up, e.g. one topology PNG per window).
    """
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight" if tight else None)
    finally:
        plt.close(fig)
    return Path(path)


def png_data_uri(fig, dpi: float = 100) -> str:
    """The figure as a `data:image/png;base64,...` URI (a page that carries its images), closed."""
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    finally:
        plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")
