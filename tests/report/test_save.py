"""Figures rendered for the report's palette PNGs: an opaque figure as drawn, a transparent one on white."""

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from satchain.report import _save


def _figure(face) -> Figure:
    fig = Figure(figsize=(2.0, 1.5), dpi=50, facecolor=face)
    ax = fig.add_axes((0.1, 0.1, 0.8, 0.8), facecolor=face)
    ax.plot([0, 1], [0, 1], color=(0.2, 0.4, 0.8), lw=6, alpha=0.5)
    return fig


def test_an_opaque_figure_is_rendered_as_drawn():
    fig = _figure("white")
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    drawn = np.asarray(canvas.buffer_rgba())
    assert drawn[..., 3].min() == 255
    rgb = np.asarray(_save._render_rgb(fig, None))
    assert np.array_equal(rgb, drawn[..., :3])


def test_a_transparent_figure_is_composited_on_white():
    fig = _figure("none")
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    drawn = np.asarray(canvas.buffer_rgba()).astype(float)
    a = drawn[..., 3:] / 255.0
    assert a.min() < 1.0  # (transparent where nothing is drawn)
    want = np.rint(drawn[..., :3] * a + 255.0 * (1.0 - a))
    rgb = np.asarray(_save._render_rgb(fig, None)).astype(float)
    assert np.max(np.abs(rgb - want)) <= 1.0  # (float32 rounding)
    assert np.all(rgb[a[..., 0] == 0.0] == 255.0)  # nothing drawn: white


def test_a_saved_figure_is_a_palette_png(tmp_path):
    path = tmp_path / "f.png"
    _save.save_figure(_figure("white"), path)
    with Image.open(path) as im:
        assert im.mode == "P" and len(im.getcolors()) <= _save.PNG_COLOURS
