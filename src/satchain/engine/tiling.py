"""Geometry of detector sampling and of the tile plan.

Coordinates on the input (ground-truth) grid are in input pixels, continuous: input pixel ``n`` covers
``[n, n + 1)``. Output (detector) pixel ``i`` along an axis has its centre at

    c_i = phase + (i + 1/2) * k,     k = GSD / input_pixel_m

and integrates the input over its *active* footprint ``[c_i - w/2, c_i + w/2)``, ``w = k * active/pitch``.
With ``phase = 0``, an integer ``k`` and 100 % fill, output pixel ``(i, j)`` integrates exactly input pixels
``[i k, (i + 1) k) x [j k, (j + 1) k)`` (the geometry contract). Axis 0 is along-track (y, ALT).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy.fft as sfft

from satchain._validate import check_positive, check_range
from satchain.errors import ConfigError

__all__ = ["AxisSampling", "Tile", "Window", "footprint_weights", "plan_tiles"]


class Window(NamedTuple):
    """A rectangle of pixels: first row, first column, height, width."""

    row0: int
    col0: int
    height: int
    width: int

    @property
    def rows(self) -> slice:
        return slice(self.row0, self.row0 + self.height)

    @property
    def cols(self) -> slice:
        return slice(self.col0, self.col0 + self.width)


@dataclass(frozen=True)
class AxisSampling:
    """Detector sampling along one axis of the input grid.

    Parameters
    ----------
    k : float
        Output pixel pitch in input pixels (GSD / input pixel size), > 0.
    fill : float
        Active width / pitch along this axis, in (0, 1].
    phase_px : float
        Position of the output grid's origin on the input grid (input px), >= 0.
    n_input : int
        Input pixels along this axis.
    """

    k: float
    fill: float
    phase_px: float
    n_input: int

    def __post_init__(self) -> None:
        check_positive("k", self.k)
        check_range("fill", self.fill, 0, 1, lo_open=True)
        check_range("phase_px", self.phase_px, 0, None)
        if self.n_input < 1:
            raise ConfigError(f"n_input = {self.n_input!r}: must be >= 1")

    @property
    def width_px(self) -> float:
        """Active footprint width in input pixels."""
        return self.k * self.fill

    @property
    def n_output(self) -> int:
        """Whole output pixels whose pitch cell lies inside the input."""
        return max(int(math.floor((self.n_input - self.phase_px) / self.k + 1e-9)), 0)

    def centres(self, i0: int, i1: int) -> np.ndarray:
        """Input-grid coordinates of the centres of output pixels ``i0 .. i1-1``."""
        return self.phase_px + (np.arange(i0, i1) + 0.5) * self.k


def footprint_weights(centres: np.ndarray, width_px: float, n0: int) -> tuple[np.ndarray, np.ndarray]:
    """Overlap weights of each footprint with the input pixels, normalised to sum to 1.

    Returns ``(index, weight)``, both of shape ``(len(centres), K)``: footprint ``i`` averages input pixels
    ``n0 + index[i, :]`` with ``weight[i, :]`` (the fraction of each pixel covered, over the footprint
    width). Exact for any width and position.

    Examples
    --------
    >>> idx, w = footprint_weights(np.array([1.5]), 3.0, 0)   # covers pixels 0, 1, 2 exactly
    >>> idx[0].tolist(), np.round(w[0], 6).tolist()
    ([0, 1, 2, 3], [0.333333, 0.333333, 0.333333, 0.0])
    """
    lo = centres - width_px / 2
    hi = centres + width_px / 2
    first = np.floor(lo + 1e-12).astype(np.int64)
    K = int(math.ceil(width_px)) + 1
    idx = first[:, None] + np.arange(K)[None, :]
    a = np.maximum(idx, lo[:, None])
    b = np.minimum(idx + 1, hi[:, None])
    w = np.clip(b - a, 0.0, None) / width_px
    return idx - n0, w


class Tile(NamedTuple):
    """One unit of decimation work: a window of the coarse grid and the fine input window (with margins)
    whose low-passed, decimated centre it is."""

    index: tuple[int, int]  # type: ignore[assignment]  # a field named as tuple.index (public: tile.index), by design
    coarse: Window
    input: Window


def plan_tiles(
    n_coarse: tuple[int, int],
    *,
    D: int,
    tile_coarse: int,
    margin_px: int,
    origin_px: tuple[int, int] = (0, 0),
    fast: bool = False,
) -> list[Tile]:
    """Cut the coarse grid (coarse sample ``j`` = fine pixel ``D j``) into square tiles of ``tile_coarse``
    samples; each reads fine pixels ``[D j0 - margin_px, D j1 + margin_px)`` (``margin_px`` a multiple of
    ``D``), offset by ``origin_px`` (the fine pixel of coarse sample 0). Input windows may extend beyond the
    ground truth: the border rule fills them. ``fast``: tiles of equal length along each axis (at most
    ``tile_coarse`` samples before stretching), each input window stretched at its far end to ``D`` times a
    fast FFT length (a longer far margin: the same coarse samples, much faster transforms).

    Examples
    --------
    >>> [tuple(t.input) for t in plan_tiles((3, 5), D=4, tile_coarse=4, margin_px=8)]
    [(-8, -8, 28, 32), (-8, 8, 28, 20)]
    """
    if tile_coarse < 1 or margin_px < 0 or margin_px % D:
        raise ConfigError(
            f"tile_coarse = {tile_coarse!r}, margin_px = {margin_px!r}: need tile_coarse >= 1 and margin_px a "
            f"non-negative multiple of D = {D}"
        )

    def length(n: int) -> int:
        return D * sfft.next_fast_len(n // D) if fast and D > 1 else n

    def step(n: int) -> int:
        """Coarse samples per tile along an axis. ``fast``: as many tiles as ``tile_coarse`` needs, of equal
        length (no short remainder tile, which costs nearly a full one), each the most samples its fast
        input window holds."""
        if not fast:
            return tile_coarse
        h = -(-n // -(-n // tile_coarse))
        return max(h, (length(D * h + 2 * margin_px) - 2 * margin_px) // D)

    sy, sx = step(n_coarse[0]), step(n_coarse[1])
    tiles = []
    for ti, j0 in enumerate(range(0, n_coarse[0], sy)):
        h = min(sy, n_coarse[0] - j0)
        for tj, i0 in enumerate(range(0, n_coarse[1], sx)):
            w = min(sx, n_coarse[1] - i0)
            tiles.append(
                Tile(
                    index=(ti, tj),
                    coarse=Window(j0, i0, h, w),
                    input=Window(
                        origin_px[0] + D * j0 - margin_px,
                        origin_px[1] + D * i0 - margin_px,
                        length(D * h + 2 * margin_px),
                        length(D * w + 2 * margin_px),
                    ),
                )
            )
    return tiles
