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


#: Tolerance (m, relative to the pixel) of a mapped point lying on a region's border.
_ON_BORDER = 1e-6


@dataclass(frozen=True)
class Frame:
    """Pixel geometry of the measured image in scene metres.

    Without ``affine`` the grid is axis-aligned: pixel ``[i, j]`` covers ``x in [ox + j p, ox + (j+1) p)``,
    ``y in [oy + i p, oy + (i+1) p)``.  With ``affine = (a, b, c, d, e, f)`` scene metres map to continuous pixel
    coordinates (pixel centres at integers) as ``col = a x + b y + c``, ``row = d x + e y + f`` (a pushbroom
    image sheared and scaled by Earth rotation or a line-rate error, :mod:`satchain.measure.auto`); ``pixel_m``
    is then the ACT ground step the measurers report frequencies with, and ``origin_m`` only a label.
    """

    pixel_m: float
    origin_m: tuple[float, float]
    shape: tuple[int, int]
    affine: tuple[float, float, float, float, float, float] | None = None

    @property
    def linear(self) -> tuple[float, float, float, float]:
        """``(a, b, d, e)``: pixels per scene metre (``d col / dx``, ``d col / dy``, ``d row / dx``, ``d row / dy``)."""
        if self.affine is None:
            return 1.0 / self.pixel_m, 0.0, 0.0, 1.0 / self.pixel_m
        a, b, _, d, e, _ = self.affine
        return a, b, d, e

    @property
    def inverse_linear(self) -> tuple[float, float, float, float]:
        """Scene metres per pixel: ``(dx/dcol, dx/drow, dy/dcol, dy/drow)``."""
        a, b, d, e = self.linear
        det = a * e - b * d
        return e / det, -b / det, -d / det, a / det

    def px(self, x_m, y_m):
        """Scene point -> continuous pixel coordinates with pixel centres at integers (x = col, y = row)."""
        if self.affine is None:
            p, (ox, oy) = self.pixel_m, self.origin_m
            return (x_m - ox) / p - 0.5, (y_m - oy) / p - 0.5
        a, b, c, d, e, f = self.affine
        return a * x_m + b * y_m + c, d * x_m + e * y_m + f

    def metres(self, col, row):
        """Continuous pixel coordinates (centres at integers) -> scene point (the inverse of :meth:`px`)."""
        if self.affine is None:
            p, (ox, oy) = self.pixel_m, self.origin_m
            return ox + (col + 0.5) * p, oy + (row + 0.5) * p
        _, _, c, _, _, f = self.affine
        ia, ib, id_, ie = self.inverse_linear
        u, v = col - c, row - f
        return ia * u + ib * v, id_ * u + ie * v

    def inside(self, bbox_m, margin_px: int = 0):
        """ROI ``(x0, y0, x1, y1)``: pixels whose footprints lie inside ``bbox_m``, less a margin.  With an
        affine, the largest axis-aligned box of pixels whose footprints lie inside the mapped ``bbox_m`` (a
        parallelogram): the largest box centred on it, then grown a pixel at a time while it stays inside."""
        if self.affine is not None:
            x0, y0, x1, y1 = self._inscribed(bbox_m, 0.5)
            return x0 + margin_px, y0 + margin_px, x1 - margin_px, y1 - margin_px
        p, (ox, oy) = self.pixel_m, self.origin_m
        xmin, ymin, xmax, ymax = (float(v) for v in bbox_m)
        x0 = math.ceil((xmin - ox) / p - 1e-9) + margin_px
        y0 = math.ceil((ymin - oy) / p - 1e-9) + margin_px
        x1 = math.floor((xmax - ox) / p + 1e-9) - margin_px
        y1 = math.floor((ymax - oy) / p + 1e-9) - margin_px
        return x0, y0, x1, y1

    def covering(self, bbox_m):
        """A pixel box ``(x0, y0, x1, y1)`` covering every pixel that ``bbox_m`` touches (and one more on each
        side without an affine: :meth:`inside` widened by one)."""
        if self.affine is None:
            x0, y0, x1, y1 = self.inside(bbox_m)
            return x0 - 1, y0 - 1, x1 + 1, y1 + 1
        cols, rows = self.px(*_corners(bbox_m))
        return (
            math.floor(min(cols) + 0.5),
            math.floor(min(rows) + 0.5),
            math.floor(max(cols) + 0.5) + 1,
            math.floor(max(rows) + 0.5) + 1,
        )

    def centres(self, lo_m: float, hi_m: float, axis: int) -> tuple[int, int]:
        """Half-open index range of the pixels whose centres lie in ``[lo_m, hi_m]`` along x (0) or y (1) (an
        axis-aligned grid only; :meth:`centres_box` in general)."""
        if self.affine is not None:
            raise ValueError("Frame.centres: the grid has an affine; use centres_box")
        o = self.origin_m[axis]
        i0 = math.ceil((lo_m - o) / self.pixel_m - 0.5 - 1e-9)
        i1 = math.floor((hi_m - o) / self.pixel_m - 0.5 + 1e-9) + 1
        return i0, i1

    def centres_box(self, bbox_m):
        """ROI ``(x0, y0, x1, y1)`` of the pixels whose centres lie in ``bbox_m`` (with an affine: the largest
        axis-aligned box of them inside the mapped ``bbox_m``, as :meth:`inside`)."""
        if self.affine is not None:
            return self._inscribed(bbox_m, 0.0)
        xmin, ymin, xmax, ymax = (float(v) for v in bbox_m)
        x0, x1 = self.centres(xmin, xmax, 0)
        y0, y1 = self.centres(ymin, ymax, 1)
        return x0, y0, x1, y1

    def centres_m(self, roi) -> tuple[np.ndarray, np.ndarray]:
        """Scene coordinates (x, y) of the centres of the pixels of ``roi = (x0, y0, x1, y1)``."""
        x0, y0, x1, y1 = roi
        ys, xs = np.mgrid[y0:y1, x0:x1]
        if self.affine is not None:
            return self.metres(xs.astype(float), ys.astype(float))
        p, (ox, oy) = self.pixel_m, self.origin_m
        return ox + (xs + 0.5) * p, oy + (ys + 0.5) * p

    def step_m(self, axis: int) -> float:
        """Scene metres along x (0) or y (1) of one pixel step along the image's columns (0) or rows (1): the
        ground sampling an axis-aligned measurement along that axis sees."""
        if self.affine is None:
            return self.pixel_m
        ia, _, _, ie = self.inverse_linear
        return abs(ia if axis == 0 else ie)

    def length_px(self, length_m: float) -> float:
        """A length in scene metres in pixels (with an affine: at its mean scale, ``sqrt |det|``)."""
        if self.affine is None:
            return length_m / self.pixel_m
        a, b, d, e = self.linear
        return length_m * math.sqrt(abs(a * e - b * d))

    def tilt(self, along: int) -> float:
        """Pixels across per pixel along, of a scene line parallel to axis ``along`` (0: x, 1: y) in the image:
        0 on an axis-aligned grid; a shear or a rotation tilts it."""
        a, b, d, e = self.linear
        return d / a if along == 0 else b / e

    def mix(self, along: int) -> float:
        """Pixels along axis ``along`` that the scene coordinate ``along`` moves per pixel across (down a column
        for ``along = 0``): 0 on an axis-aligned grid."""
        ia, ib, id_, ie = self.inverse_linear
        return ib / ia if along == 0 else id_ / ie

    def anisotropy(self) -> float:
        """``s_max / s_min - 1`` of the linear part's singular values: 0 for a rotation and uniform scale."""
        a, b, d, e = self.linear
        s = np.linalg.svd(np.array([[a, b], [d, e]]), compute_uv=False)
        return float(s[0] / s[1] - 1.0)

    def _inscribed(self, bbox_m, half: float):
        """The box ``(x0, y0, x1, y1)`` whose points ``x0 - half .. x1 - 1 + half`` (rows likewise) lie inside
        the mapped ``bbox_m``: the largest centred one, grown a pixel at a time while it stays inside."""
        xmin, ymin, xmax, ymax = (float(v) for v in bbox_m)
        cx, cy = self.px(0.5 * (xmin + xmax), 0.5 * (ymin + ymax))
        ha, hb = _centred_rectangle(self.inverse_linear, 0.5 * (xmax - xmin), 0.5 * (ymax - ymin))
        box = [
            math.ceil(cx - ha + half - 1e-9),
            math.ceil(cy - hb + half - 1e-9),
            math.floor(cx + ha - half + 1e-9) + 1,
            math.floor(cy + hb - half + 1e-9) + 1,
        ]
        tol = _ON_BORDER * self.pixel_m

        def fits(bx) -> bool:
            us = (bx[0] - half, bx[2] - 1 + half)
            vs = (bx[1] - half, bx[3] - 1 + half)
            xs, ys = self.metres(np.array([u for u in us for _ in vs]), np.array([v for _ in us for v in vs]))
            return bool(
                bx[2] > bx[0]
                and bx[3] > bx[1]
                and np.all((xs >= xmin - tol) & (xs <= xmax + tol) & (ys >= ymin - tol) & (ys <= ymax + tol))
            )

        grown = fits(box)
        while grown:
            grown = False
            for k, step in ((0, -1), (1, -1), (2, 1), (3, 1)):
                trial = list(box)
                trial[k] += step
                if fits(trial):
                    box, grown = trial, True
        return tuple(box)

    def check_roi(self, roi) -> None:
        x0, y0, x1, y1 = roi
        ny, nx = self.shape
        if not (0 <= x0 < x1 <= nx and 0 <= y0 < y1 <= ny):
            raise Skip(
                f"region {tuple(int(v) for v in roi)} (x0, y0, x1, y1) is not inside the image "
                f"({nx} x {ny} px): the item lies outside or across the image border"
            )


def _corners(bbox_m) -> tuple[np.ndarray, np.ndarray]:
    xmin, ymin, xmax, ymax = (float(v) for v in bbox_m)
    return np.array([xmin, xmax, xmin, xmax]), np.array([ymin, ymin, ymax, ymax])


def _centred_rectangle(inv, hx: float, hy: float) -> tuple[float, float]:
    """Half-sides ``(A, B)`` (px) of the largest-area axis-aligned rectangle centred in the image of the box
    ``|x| <= hx, |y| <= hy`` under the linear map whose inverse is ``inv = (ia, ib, id, ie)``: maximise ``A B``
    under ``|ia| A + |ib| B <= hx`` and ``|id| A + |ie| B <= hy`` (its corners inside; the optimum lies on one
    constraint at that line's own maximum, or where the two meet)."""
    rows = [(abs(inv[0]), abs(inv[1]), hx), (abs(inv[2]), abs(inv[3]), hy)]
    cands = []
    for p, q, h in rows:
        if p > 0 and q > 0:
            cands.append((h / (2 * p), h / (2 * q)))
    (p1, q1, h1), (p2, q2, h2) = rows
    det = p1 * q2 - q1 * p2
    if det != 0:
        cands.append(((h1 * q2 - q1 * h2) / det, (p1 * h2 - h1 * p2) / det))
    best = (0.0, 0.0)
    for a_, b_ in cands:
        ok = a_ >= 0 and b_ >= 0 and all(p * a_ + q * b_ <= h * (1 + 1e-12) for p, q, h in rows)
        if ok and a_ * b_ > best[0] * best[1]:
            best = (a_, b_)
    return best


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
    row_offsets_px: tuple | None = None  # per image row (du, dv): a moving line of sight's displaced rows
