"""Atomic saving of report artefacts (text, figures), on top of :func:`satchain.io.atomic_path`.

Figures are made with matplotlib's object-oriented API (:class:`matplotlib.figure.Figure`), never through
pyplot's global state, so satchain neither needs nor switches a backend (``matplotlib.use("Agg")`` at import
would silence a notebook's figures). :data:`figure_api` offers the two pyplot names the plotting modules use,
``subplots`` and ``Rectangle``, on top of that API.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from satchain.io import atomic_path

__all__ = ["atomic_path", "figure_api", "new_figure", "save_figure", "subplots", "write_text"]


def new_figure(**kwargs):
    """A :class:`matplotlib.figure.Figure` not registered with pyplot (headless, no backend switch)."""
    from matplotlib.figure import Figure

    return Figure(**kwargs)


def subplots(nrows: int = 1, ncols: int = 1, *, figsize=None, dpi=None, **kwargs):
    """``pyplot.subplots`` without pyplot: ``(figure, axes)``."""
    fig = new_figure(figsize=figsize, dpi=dpi)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def _rectangle(*args, **kwargs):
    from matplotlib.patches import Rectangle

    return Rectangle(*args, **kwargs)


#: The pyplot names the plotting modules use (``plt.subplots``, ``plt.Rectangle``), without pyplot.
figure_api = SimpleNamespace(subplots=subplots, Rectangle=_rectangle)


def write_text(path: str | Path, text: str) -> None:
    """Atomically write a text file (its directory is created)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def save_figure(fig, path: str | Path, **kwargs) -> None:
    """Atomically save a matplotlib figure (format from the suffix) and release it."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=Path(path).suffix.lstrip(".") or "png", **kwargs)
    finally:
        fig.clear()
