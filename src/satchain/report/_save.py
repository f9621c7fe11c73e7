"""Atomic saving of report artefacts (text, figures), on top of :func:`satchain.io.images.atomic_path`."""

from __future__ import annotations

from pathlib import Path

from satchain.io.images import PNG_COMPRESS_LEVEL, atomic_path

__all__ = ["PNG_COLOURS", "atomic_path", "save_figure", "write_text"]

#: Colours of the palette a PNG figure is quantised to.
PNG_COLOURS = 256


def write_text(path: str | Path, text: str) -> None:
    """Atomically write a text file (its directory is created)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def save_figure(fig, path: str | Path, **kwargs) -> None:
    """Atomically save a matplotlib figure (format from the suffix) and close it.

    ``fig`` may be a :class:`matplotlib.figure.Figure` made without pyplot (then nothing global is touched)
    or one made by pyplot (then it is closed there). A PNG is written with a palette of at most
    :data:`PNG_COLOURS` colours (no dithering): line plots and grey images lose nothing visible and weigh
    about a third, which keeps the self-contained report light."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    try:
        with atomic_path(path) as tmp:
            if fmt == "png":
                _save_palette_png(fig, tmp, **kwargs)
            else:
                fig.savefig(tmp, format=fmt, **kwargs)
    finally:
        if getattr(fig.canvas, "manager", None) is not None:
            import matplotlib.pyplot as plt

            plt.close(fig)


def _render_rgb(fig, dpi: float | None):
    """``fig`` drawn by Agg at ``dpi`` (the figure's own when None) on white, as a PIL RGB image: no PNG
    encoded and decoded on the way."""
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    old_dpi = fig.dpi
    if dpi is not None:
        fig.set_dpi(dpi)
    try:
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        rgba = np.asarray(canvas.buffer_rgba())
    finally:
        if dpi is not None:
            fig.set_dpi(old_dpi)
    if rgba[..., 3].min() == 255:  # opaque (a figure's white face): on white it is itself, alpha dropped
        return Image.fromarray(rgba, "RGBA").convert("RGB")
    a = rgba[..., 3:4].astype(np.float32) / 255.0  # composite on white
    rgb = rgba[..., :3].astype(np.float32) * a + 255.0 * (1.0 - a)
    return Image.fromarray(np.rint(rgb).astype(np.uint8), "RGB")


def _save_palette_png(fig, path: Path, **kwargs) -> None:
    """Render ``fig`` and write it as a PNG quantised to a palette of :data:`PNG_COLOURS` colours."""
    from PIL import Image

    if set(kwargs) - {"dpi"}:  # savefig's other options (bbox_inches, ...): through savefig
        import io

        buf = io.BytesIO()
        fig.savefig(buf, format="png", **kwargs)
        buf.seek(0)
        with Image.open(buf) as im:
            rgba = im.convert("RGBA")
        rgb = Image.alpha_composite(Image.new("RGBA", rgba.size, "white"), rgba).convert("RGB")
    else:
        rgb = _render_rgb(fig, kwargs.get("dpi"))
    q = rgb.quantize(colors=PNG_COLOURS, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
    q.save(path, format="PNG", compress_level=PNG_COMPRESS_LEVEL)
