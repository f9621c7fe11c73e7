"""What the parts of :func:`satchain.measure.auto.measure_auto` share: the pixel geometry of the measured image in
scene metres, the context and the result record of a per-kind measurer, the skip record."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the per-kind results (typing only: measurers import this module)
    from satchain.measure.bars import BarsResult
    from satchain.measure.edge import EdgeResult
    from satchain.measure.star import StarResult
    from satchain.measure.wedge import WedgeResult

__all__ = ["AutoContext", "AutoItem", "Frame", "Skip", "skip_entry"]


@dataclass(frozen=True)
class AutoItem:
    """One measured item: its truth id and kind, the core result object and its JSON summary."""

    id: str
    kind: str
    result: EdgeResult | StarResult | BarsResult | WedgeResult
    summary: dict


class Skip(Exception):
    """An item that cannot be measured; the message is the reason."""


def skip_entry(ident: str, kind: str, reason: str) -> dict:
    """One entry of ``AutoResult.skipped``."""
    return {"id": ident, "kind": kind, "reason": reason}


@dataclass(frozen=True)
class Frame:
    """Pixel geometry of the measured image in scene metres."""

    pixel_m: float
    origin_m: tuple[float, float]
    shape: tuple[int, int]

    def px(self, x_m: float, y_m: float) -> tuple[float, float]:
        """Scene point -> continuous pixel coordinates with pixel centres at integers (x = col, y = row)."""
        p, (ox, oy) = self.pixel_m, self.origin_m
        return (x_m - ox) / p - 0.5, (y_m - oy) / p - 0.5

    def inside(self, bbox_m, margin_px: int = 0):
        """ROI ``(x0, y0, x1, y1)``: pixels whose footprints lie inside ``bbox_m``, less a margin."""
        p, (ox, oy) = self.pixel_m, self.origin_m
        xmin, ymin, xmax, ymax = (float(v) for v in bbox_m)
        x0 = math.ceil((xmin - ox) / p - 1e-9) + margin_px
        y0 = math.ceil((ymin - oy) / p - 1e-9) + margin_px
        x1 = math.floor((xmax - ox) / p + 1e-9) - margin_px
        y1 = math.floor((ymax - oy) / p + 1e-9) - margin_px
        return x0, y0, x1, y1

    def centres(self, lo_m: float, hi_m: float, axis: int) -> tuple[int, int]:
        """Half-open index range of the pixels whose centres lie in ``[lo_m, hi_m]`` along x (0) or y (1)."""
        o = self.origin_m[axis]
        i0 = math.ceil((lo_m - o) / self.pixel_m - 0.5 - 1e-9)
        i1 = math.floor((hi_m - o) / self.pixel_m - 0.5 + 1e-9) + 1
        return i0, i1

    def centres_m(self, roi) -> tuple[np.ndarray, np.ndarray]:
        """Scene coordinates (x, y) of the centres of the pixels of ``roi = (x0, y0, x1, y1)``."""
        x0, y0, x1, y1 = roi
        p, (ox, oy) = self.pixel_m, self.origin_m
        ys, xs = np.mgrid[y0:y1, x0:x1]
        return ox + (xs + 0.5) * p, oy + (ys + 0.5) * p

    def check_roi(self, roi) -> None:
        x0, y0, x1, y1 = roi
        ny, nx = self.shape
        if not (0 <= x0 < x1 <= nx and 0 <= y0 < y1 <= ny):
            raise Skip(
                f"region {tuple(int(v) for v in roi)} (x0, y0, x1, y1) is not inside the image "
                f"({nx} x {ny} px): the item lies outside or across the image border"
            )


@dataclass(frozen=True)
class AutoContext:
    """What every per-kind measurer is given besides its truth item: the image as given (``raw``), the image
    calibrated to reflectance (``refl``), its geometry, whether the calibration was fitted, and the options
    of :func:`~satchain.measure.auto.measure_auto`."""

    raw: np.ndarray
    refl: np.ndarray
    frame: Frame
    calibrated: bool
    wedge_threshold: float
    full_scale: float | None = None  # the sensor's full scale in the image's units (None: unknown) ...
    full_scale_refl: float | None = None  # ... and in the calibrated reflectance the star/bars/wedge read
