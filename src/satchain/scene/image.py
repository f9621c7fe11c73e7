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

from satchain._safety import check_memory
from satchain._validate import as_float_array, check_positive, check_range
from satchain.errors import ConfigError, InputError
from satchain.io.images import ImageReader, integer_scale, open_image
from satchain.scene.shapes import Window, check_window

__all__ = ["ImageScene"]


class _ArrayReader:
    def __init__(self, array):
        self.array = as_float_array("image", array, ndim=2)
        self.shape, self.dtype = tuple(int(v) for v in self.array.shape), np.asarray(array).dtype

    def read(self, row0, col0, height, width):
        return self.array[row0 : row0 + height, col0 : col0 + width]


class ImageScene:
    """A 2-D image (array or TIFF/GeoTIFF/PNG/NPY file) used as ground truth.

    A file is read window by window (tiled/stripped TIFF, GeoTIFF, BigTIFF; memory-mapped NPY and
    uncompressed TIFF), so an image far larger than memory can be simulated; only PNG is read whole.

    Parameters
    ----------
    source : ndarray or path
    pixel_m : ground size of one pixel (m); default: read from the file's metadata (GeoTIFF
        ModelPixelScale, satchain description, PNG text/pHYs). Required for arrays and NPY.
    scale : multiply stored values by this to get reflectance. Default (None): integer images are
        scaled by ``1 / (2**bits - 1)`` (8-bit 0..255 and 16-bit 0..65535 -> 0..1; ``bits`` from the
        file's ``bit_depth`` metadata or BitsPerSample, see :func:`satchain.io.images.integer_scale`), floats by 1.
    valid_range : (lo, hi) reflectance allowed after scaling; a window outside it is an InputError
        (``satchain simulate`` uses (-0.5, 4): values of 255 or 65535 are not reflectance).

    Examples
    --------
    >>> s = ImageScene(np.arange(12.0).reshape(3, 4), pixel_m=0.1)
    >>> s.extent_m, s.shape_px()
    ((0.4, 0.30000000000000004), (3, 4))
    >>> s.render((1, 1, 2, 2), pixel_m=0.1).tolist()
    [[5.0, 6.0], [9.0, 10.0]]
    >>> ImageScene(np.array([[0, 255]], np.uint8), pixel_m=1.0).render().tolist()
    [[0.0, 1.0]]
    """

    name = "image"

    def __init__(
        self,
        source,
        pixel_m: float | None = None,
        *,
        scale: float | None = None,
        valid_range: tuple[float, float] | None = None,
    ):
        meta: dict = {}
        self._reader: ImageReader | _ArrayReader
        if isinstance(source, (str, os.PathLike)):
            self._reader = open_image(source)
            meta = self._reader.meta
            self.name = os.path.basename(os.fspath(source))
        else:
            self._reader = _ArrayReader(source)
        if pixel_m is None:
            pixel_m = meta.get("pixel_m")
            if "invalid_pixel_m" in meta:
                raise ConfigError(
                    f"pixel_m: the image {self.name!r} gives {meta['invalid_pixel_m']!r}, not a ground pixel size in "
                    "(0, 1e6] m; pass pixel_m in m (--scene-pixel-m on the CLI)"
                )
            if pixel_m is None:
                raise ConfigError(
                    "pixel_m = None: the image states no pixel size; pass pixel_m in m (--scene-pixel-m on the CLI)"
                )
        self.pixel_m = check_range("pixel_m", pixel_m, 0.0, 1e6, lo_open=True)
        if self._reader.shape[0] < 1 or self._reader.shape[1] < 1:
            raise InputError("image: is empty")
        if scale is None:
            scale = integer_scale(self._reader.dtype, meta)
        self.scale = check_positive("--input-scale", scale)
        self.valid_range = valid_range
        self.metadata = meta

    @property
    def _shape(self) -> tuple[int, int]:
        return self._reader.shape

    @property
    def extent_m(self) -> tuple[float, float]:
        """(width_m, height_m)."""
        return (self._shape[1] * self.pixel_m, self._shape[0] * self.pixel_m)

    def shape_px(self, pixel_m: float | None = None) -> tuple[int, int]:
        """(rows, cols); only the native pixel size is allowed."""
        self._check_pixel(pixel_m)
        return self._shape

    def _check_pixel(self, pixel_m):
        if pixel_m is not None and not math.isclose(pixel_m, self.pixel_m, rel_tol=1e-9):
            raise ConfigError(
                f"pixel_m = {pixel_m}: an ImageScene renders only at its native pixel size "
                f"{self.pixel_m} m; resample the image upstream"
            )

    def render(self, window: Window | None = None, *, pixel_m: float | None = None) -> np.ndarray:
        """The image's pixels in ``window`` as reflectance (float32, read from the file window by window)."""
        self._check_pixel(pixel_m)
        rows, cols = self._shape
        if window is None:
            check_memory(8.0 * rows * cols, f"image {self.name!r} rendered whole ({rows} x {cols} px)")
            window = (0, 0, rows, cols)
        r0, c0, h, w = check_window(window)
        if r0 < 0 or c0 < 0 or r0 + h > rows or c0 + w > cols:
            raise InputError(f"window = {window!r}: outside the image of shape ({rows}, {cols})")
        block = np.asarray(self._reader.read(r0, c0, h, w), dtype=np.float32) * np.float32(self.scale)
        if not np.all(np.isfinite(block)):
            raise InputError(f"image {self.name!r}: window {tuple(window)} holds NaN/inf; ground truth must be finite")
        if self.valid_range is not None:
            lo, hi = float(block.min()), float(block.max())
            if lo < self.valid_range[0] or hi > self.valid_range[1]:
                raise InputError(
                    f"image {self.name!r}: values {lo:g}..{hi:g} (x scale {self.scale:g}) in window {tuple(window)} "
                    f"are not reflectance (allowed {self.valid_range[0]:g}..{self.valid_range[1]:g}); "
                    "give --input-scale, e.g. 0.00392157 (1/255) for 8-bit values stored as floats"
                )
        return block

    def truth(self, pixel_m: float | None = None, window: Window | None = None) -> dict:
        """A truth record without items (a real image has no known targets)."""
        self._check_pixel(pixel_m)
        window = (0, 0, *self._shape) if window is None else check_window(window)
        return {
            "format": "satchain-scene-truth/1",
            "scene": self.name,
            "pixel_m": self.pixel_m,
            "extent_m": list(self.extent_m),
            "shape_px": list(self._shape),
            "window_px": list(window),
            "items": [],
        }
