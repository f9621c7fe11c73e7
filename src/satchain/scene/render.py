"""Render a scene to files, streaming: tiled (Big)TIFF, downsampled PNG preview and the truth JSON.

Memory is bounded by one block of ``tile_px`` rows x ``_BLOCK_COLS`` columns plus the preview (at most
``preview_max_px`` on a side), whatever the scene size.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from satchain._validate import check_positive
from satchain.errors import ConfigError
from satchain.io.images import atomic_path, write_png, write_tiff_tiles
from satchain.scene.layout import Scene, check_scene_pixel, load_layout
from satchain.scene.shapes import Window, check_window

__all__ = ["parse_cli_window", "render_scene_to_file"]

_BLOCK_COLS = 4096


def parse_cli_window(text: str) -> Window:
    """CLI ``X0,Y0,W,H`` (pixels: X0 = column, Y0 = row) -> ``(row0, col0, height, width)``.

    Examples
    --------
    >>> parse_cli_window("100,20,64,32")
    (20, 100, 32, 64)
    """
    try:
        x0, y0, w, h = (int(v) for v in str(text).split(","))
    except ValueError:
        raise ConfigError(f"window = {text!r}: must be X0,Y0,W,H (integers, pixels)") from None
    return check_window((y0, x0, h, w))


def _blocks(window: Window, tile: int):
    row0, col0, h, w = window
    block = max(tile, (_BLOCK_COLS // tile) * tile)
    for r in range(0, h, tile):
        for c in range(0, w, block):
            yield r, c, min(tile, h - r), min(block, w - c)


def render_scene_to_file(
    layout: Scene | str | os.PathLike,
    out_path: str | os.PathLike,
    *,
    pixel_m: float | None = None,
    window: Window | None = None,
    progress: Callable[[int, int], None] | None = None,
    tile_px: int = 256,
    preview_max_px: int = 2048,
) -> dict[str, Path]:
    """Write ``OUT.tif``, ``OUT.png`` (preview) and ``OUT.truth.json`` for a scene, atomically.

    Parameters
    ----------
    layout : Scene, "paper" or path to a .toml/.json scene file
    out_path : path of the TIFF; the preview and truth file sit beside it (``OUT.png``, ``OUT.truth.json``)
    pixel_m : render pixel size (m); default: the layout's ``pixel_m`` (0.035 for "paper")
    window : (row0, col0, height, width) in pixels; default: the whole scene. From the CLI's
        ``X0,Y0,W,H`` use :func:`parse_cli_window`.
    progress : called as ``progress(done_px, total_px)`` after each block
    tile_px : TIFF tile size (multiple of 16)
    preview_max_px : the preview's longest side is at most this (area-averaged blocks of ``f x f``)

    Returns
    -------
    dict with keys "tiff", "png", "truth" (paths written).

    Notes
    -----
    The TIFF is float32 reflectance, tiled, BigTIFF above 2 GB, with GeoTIFF pixel-scale/tie-point tags
    placing the window's top-left corner at model ``(col0 * p, -row0 * p)`` (see :mod:`satchain.io.images`).
    """
    scene = layout if isinstance(layout, Scene) else load_layout(layout)
    p = scene.pixel_m if pixel_m is None else check_positive("pixel_m", pixel_m)
    check_scene_pixel(scene, p, name="pixel_m")
    window = (0, 0, *scene.shape_px(p)) if window is None else check_window(window)
    if tile_px % 16 or tile_px < 16:
        raise ConfigError(f"tile_px = {tile_px}: must be a positive multiple of 16")
    row0, col0, h, w = window
    tif = Path(out_path)
    stem = tif.with_suffix("") if tif.suffix.lower() in (".tif", ".tiff") else tif
    png, truth_path = Path(f"{stem}.png"), Path(f"{stem}.truth.json")
    f = max(1, math.ceil(max(h, w) / check_positive("preview_max_px", preview_max_px)))
    ph, pw = math.ceil(h / f), math.ceil(w / f)
    sums = np.zeros(ph * pw)
    counts = np.zeros(ph * pw)
    done = [0]

    def tiles():
        for r, c, bh, bw in _blocks(window, tile_px):
            block = scene.render((row0 + r, col0 + c, bh, bw), pixel_m=p)
            rr = (r + np.arange(bh)) // f
            cc = (c + np.arange(bw)) // f
            idx = (rr[:, None] * pw + cc[None, :]).ravel()
            sums[:] += np.bincount(idx, weights=block.ravel().astype(np.float64), minlength=ph * pw)
            counts[:] += np.bincount(idx, minlength=ph * pw)
            done[0] += bh * bw
            if progress is not None:
                progress(done[0], h * w)
            for k in range(0, bw, tile_px):
                yield block[:, k : k + tile_px]

    meta = {"scene": scene.name, "window_px": list(window), "units": "reflectance"}
    write_tiff_tiles(
        tif,
        tiles(),
        shape=(h, w),
        dtype=np.float32,
        tile=(tile_px, tile_px),
        pixel_m=p,
        origin_m=(col0 * p, row0 * p),
        metadata=meta,
    )
    preview = (sums / np.maximum(counts, 1)).reshape(ph, pw)
    write_png(
        png,
        np.round(np.clip(preview, 0.0, 1.0) * 255).astype(np.uint8),
        pixel_m=p * f,
        metadata={"preview_of": tif.name, "downsample": f},
    )
    truth = scene.truth(p, window)
    truth["files"] = {"tiff": tif.name, "preview_png": png.name, "preview_downsample": f}
    with atomic_path(truth_path) as tmp:
        tmp.write_text(json.dumps(truth, indent=1), encoding="utf-8")
    return {"tiff": tif, "png": png, "truth": truth_path}
