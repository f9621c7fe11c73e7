"""Real imagery as ground truth (the paper first used airborne images), behind the same interface as Scene.

``ImageScene`` holds a reflectance image with a known pixel size. It renders only at its native pixel
size: resampling a real image to another pixel size cannot add detail and would hide the choice of
interpolator inside the chain, so ``render(..., pixel_m=other)`` raises ConfigError; resample upstream.
Pixels of a window outside the image are an InputError (a real image has nothing there).
"""

from __future__ import annotations

import math
import os

import numpy as np

from satchain._validate import as_float_array, check_positive
from satchain.errors import ConfigError, InputError
from satchain.io import read_image
from satchain.scene.shapes import Window, check_window

__all__ = ["ImageScene"]


class ImageScene:
    """A 2-D image (array or TIFF/GeoTIFF/PNG/NPY file) used as ground truth.

    Parameters
    ----------
    source : ndarray or path
    pixel_m : ground size of one pixel (m); default: read from the file's metadata (GeoTIFF
        ModelPixelScale, satchain description, PNG text/pHYs). Required for arrays and NPY.
    scale : multiply values by this (e.g. ``1 / 255`` for 8-bit reflectance), default 1.

    Examples
    --------
    >>> s = ImageScene(np.arange(12.0).reshape(3, 4), pixel_m=0.1)
    >>> s.extent_m, s.shape_px()
    ((0.4, 0.30000000000000004), (3, 4))
    >>> s.render((1, 1, 2, 2), pixel_m=0.1).tolist()
    [[5.0, 6.0], [9.0, 10.0]]
    """

    name = "image"

    def __init__(self, source, pixel_m: float | None = None, *, scale: float = 1.0):
        meta: dict = {}
        if isinstance(source, (str, os.PathLike)):
            array, meta = read_image(source)
            self.name = os.path.basename(os.fspath(source))
        else:
            array = source
        if pixel_m is None:
            pixel_m = meta.get("pixel_m")
            if pixel_m is None:
                raise ConfigError("pixel_m = None: the image states no pixel size; pass pixel_m (m)")
        self.pixel_m = check_positive("pixel_m", pixel_m)
        image = as_float_array("image", array, ndim=2) * float(scale)
        if image.size == 0:
            raise InputError("image: is empty")
        self._image = image.astype(np.float32)
        self.metadata = meta

    @property
    def extent_m(self) -> tuple[float, float]:
        """(width_m, height_m)."""
        return (self._image.shape[1] * self.pixel_m, self._image.shape[0] * self.pixel_m)

    def shape_px(self, pixel_m: float | None = None) -> tuple[int, int]:
        """(rows, cols); only the native pixel size is allowed."""
        self._check_pixel(pixel_m)
        return self._image.shape  # type: ignore[return-value]

    def _check_pixel(self, pixel_m):
        if pixel_m is not None and not math.isclose(pixel_m, self.pixel_m, rel_tol=1e-9):
            raise ConfigError(
                f"pixel_m = {pixel_m}: an ImageScene renders only at its native pixel size "
                f"{self.pixel_m} m; resample the image upstream"
            )

    def render(self, window: Window | None = None, *, pixel_m: float | None = None) -> np.ndarray:
        """The image's pixels in ``window`` (float32 copy)."""
        self._check_pixel(pixel_m)
        rows, cols = self._image.shape
        if window is None:
            return self._image.copy()
        r0, c0, h, w = check_window(window)
        if r0 < 0 or c0 < 0 or r0 + h > rows or c0 + w > cols:
            raise InputError(f"window = {window!r}: outside the image of shape ({rows}, {cols})")
        return self._image[r0 : r0 + h, c0 : c0 + w].copy()

    def truth(self, pixel_m: float | None = None, window: Window | None = None) -> dict:
        """A truth record without items (a real image has no known targets)."""
        self._check_pixel(pixel_m)
        window = (0, 0, *self._image.shape) if window is None else check_window(window)
        return {
            "format": "satchain-scene-truth/1",
            "scene": self.name,
            "pixel_m": self.pixel_m,
            "extent_m": list(self.extent_m),
            "shape_px": list(self._image.shape),
            "window_px": list(window),
            "items": [],
        }
