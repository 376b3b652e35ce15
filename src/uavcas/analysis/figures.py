"""Figure output shared by analysis and IDS: matplotlib without a display, PNGs written atomically."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless machines, CI: never try to open a display

import matplotlib.pyplot as plt  # noqa: E402

from uavcas.atomic import atomic_path  # noqa: E402


def save_png(fig, path: str | Path, dpi: int = 120) -> Path:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return Path(path)
