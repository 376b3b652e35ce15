"""The one figure saver: no display, whole PNGs or nothing, figures closed."""

from __future__ import annotations

import struct

import matplotlib
import pytest

from uavcas.figure import plt, save_png

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _png_size(path) -> tuple[int, int]:
    head = path.read_bytes()[:24]
    assert head[:8] == PNG_MAGIC
    return struct.unpack(">II", head[16:24])


def test_headless_backend_and_figure_closed(tmp_path):
    assert matplotlib.get_backend().lower() == "agg"
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [1, 0])
    out = save_png(fig, tmp_path / "sub" / "a.png")
    assert out == tmp_path / "sub" / "a.png" and _png_size(out)[0] > 0
    assert fig.number not in plt.get_fignums()


def test_full_canvas_keeps_the_figure_size(tmp_path):
    sizes = []
    for label in ("short", "a much longer title that a tight box would crop differently"):
        fig, ax = plt.subplots(figsize=(6.4, 5.6), dpi=110)
        ax.set_title(label)
        sizes.append(_png_size(save_png(fig, tmp_path / f"{len(label)}.png", dpi="figure", tight=False)))
    assert sizes == [(704, 616), (704, 616)]


def test_a_failed_draw_leaves_the_previous_file_and_no_temporary(tmp_path):
    target = tmp_path / "fig.png"
    target.write_bytes(b"previous")
    fig, ax = plt.subplots()
    ax.set_title(r"$\frac{$")  # mathtext that cannot be parsed: the draw fails inside savefig
    with pytest.raises(ValueError):
        save_png(fig, target)
    assert fig.number not in plt.get_fignums()
    assert target.read_bytes() == b"previous" and sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]
