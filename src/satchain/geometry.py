"""One rectangle type for pixel regions: windows ``(row0, col0, height, width)`` and ROIs ``(x0, y0, x1, y1)``.

Both conventions exist in satchain (scene windows are row-major with a size, measurement ROIs are x/y corners,
half-open); :class:`Rect` holds the region once and converts to and from either, so the two cannot be mixed up.

Examples
--------
>>> r = Rect.from_roi((5, 2, 25, 12))
>>> r.to_window(), r.shape
((2, 5, 10, 20), (10, 20))
>>> import numpy as np
>>> np.arange(600).reshape(20, 30)[r.slices].shape
(10, 20)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from satchain.errors import InputError

__all__ = ["Rect", "as_rect"]


def _ints(name: str, values, n: int = 4) -> tuple[int, ...]:
    try:
        out = tuple(int(v) for v in values)
        exact = all(float(v) == o for v, o in zip(values, out, strict=True))
    except (TypeError, ValueError):
        out, exact = (), False
    if len(out) != n or not exact:
        raise InputError(f"{name} = {values!r}: must be {n} integers")
    return out


@dataclass(frozen=True, order=True)
class Rect:
    """A half-open pixel rectangle: rows ``row0 <= i < row1``, columns ``col0 <= j < col1`` (row = y = ALT,
    column = x = ACT). Empty or inverted rectangles are refused."""

    row0: int
    col0: int
    row1: int
    col1: int

    def __post_init__(self):
        vals = _ints("Rect", (self.row0, self.col0, self.row1, self.col1))
        if not (vals[0] < vals[2] and vals[1] < vals[3]):
            raise InputError(f"Rect(row0={vals[0]}, col0={vals[1]}, row1={vals[2]}, col1={vals[3]}): must be non-empty")
        for name, v in zip(("row0", "col0", "row1", "col1"), vals, strict=True):
            object.__setattr__(self, name, v)

    @classmethod
    def from_roi(cls, roi: Sequence[int]) -> Rect:
        """From ``(x0, y0, x1, y1)`` (half-open; x = column)."""
        x0, y0, x1, y1 = _ints("roi", roi)
        return cls(y0, x0, y1, x1)

    @classmethod
    def from_window(cls, window: Sequence[int]) -> Rect:
        """From ``(row0, col0, height, width)``."""
        r, c, h, w = _ints("window", window)
        return cls(r, c, r + h, c + w)

    def to_roi(self) -> tuple[int, int, int, int]:
        """``(x0, y0, x1, y1)``."""
        return (self.col0, self.row0, self.col1, self.row1)

    def to_window(self) -> tuple[int, int, int, int]:
        """``(row0, col0, height, width)``."""
        return (self.row0, self.col0, self.height, self.width)

    @property
    def height(self) -> int:
        return self.row1 - self.row0

    @property
    def width(self) -> int:
        return self.col1 - self.col0

    @property
    def shape(self) -> tuple[int, int]:
        return (self.height, self.width)

    @property
    def rows(self) -> slice:
        return slice(self.row0, self.row1)

    @property
    def cols(self) -> slice:
        return slice(self.col0, self.col1)

    @property
    def slices(self) -> tuple[slice, slice]:
        """``image[rect.slices]`` is the region."""
        return (self.rows, self.cols)

    def inside(self, shape: Sequence[int]) -> bool:
        """Whether the rectangle lies within an array of ``shape`` (rows, cols)."""
        return self.row0 >= 0 and self.col0 >= 0 and self.row1 <= shape[0] and self.col1 <= shape[1]


def as_rect(value, *, kind: str = "roi") -> Rect:
    """A Rect from a Rect, or from a 4-sequence read as ``kind`` (``"roi"`` or ``"window"``)."""
    if isinstance(value, Rect):
        return value
    return Rect.from_roi(value) if kind == "roi" else Rect.from_window(value)
