"""Atomic saving of report artefacts (text, figures), on top of :func:`satchain.io.atomic_path`."""

from __future__ import annotations

from pathlib import Path

from satchain.io import atomic_path

__all__ = ["atomic_path", "save_figure", "write_text"]


def write_text(path: str | Path, text: str) -> None:
    """Atomically write a text file (its directory is created)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def save_figure(fig, path: str | Path, **kwargs) -> None:
    """Atomically save a matplotlib figure (format from the suffix) and close it.

    ``fig`` may be a :class:`matplotlib.figure.Figure` made without pyplot (then nothing global is touched)
    or one made by pyplot (then it is closed there)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=Path(path).suffix.lstrip(".") or "png", **kwargs)
    finally:
        if getattr(fig.canvas, "manager", None) is not None:
            import matplotlib.pyplot as plt

            plt.close(fig)
