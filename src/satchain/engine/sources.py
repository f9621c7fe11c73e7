"""Ground-truth sources the engine reads window by window, and the border rule.

A *source* is any object with ``pixel_m`` (ground size of one input pixel, m), ``shape_px`` ((rows, cols))
and ``read(window) -> 2-D float array`` for windows inside ``[0, rows) x [0, cols)``. Scenes render such
windows on the fly (so a scene never has to exist in full); :class:`ArraySource` wraps an in-memory or
memory-mapped array.

Outside the source the engine needs context for the PSF; :func:`read_with_border` supplies it by the
border rule: ``"symmetric"`` (mirror about the edge, the default: no artificial edge at the border),
``"periodic"`` (wrap around, as a full-frame FFT assumes) or ``"constant"`` (a fixed reflectance).
"""

from __future__ import annotations

import contextlib
import mmap
from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np

from satchain._validate import check_choice, check_positive, split_mask
from satchain.engine.tiling import Window
from satchain.errors import InputError

__all__ = [
    "BORDER_RULES",
    "ArraySource",
    "BorderedWindow",
    "GroundTruth",
    "SceneSource",
    "as_ground_truth",
    "read_with_border",
    "reflectance_gain",
    "release_pages",
]

BORDER_RULES = ("symmetric", "periodic", "constant")


def release_pages(array) -> None:
    """Flush a disk-backed array (:class:`numpy.memmap`) and drop its pages from this process's resident memory;
    the data stays in the file (and the OS page cache). The streamed path calls it after every tile it writes to
    or reads from its coarse grid on disk, so its peak RSS is its working set, not the grid's size. A no-op for
    an in-memory array (or where the OS has no ``madvise``)."""
    mm = getattr(array, "_mmap", None)
    if mm is None or not hasattr(mm, "madvise") or not hasattr(mmap, "MADV_DONTNEED"):
        return
    with contextlib.suppress(OSError, ValueError):
        array.flush()
        mm.madvise(mmap.MADV_DONTNEED)


@runtime_checkable
class GroundTruth(Protocol):
    """What the engine reads: a rectangular raster of reflectance (or radiance) at ``pixel_m``."""

    pixel_m: float
    shape_px: tuple[int, int]

    def read(self, window: Window) -> np.ndarray: ...


def reflectance_gain(dtype, input_scale: float | None = None) -> float:
    """The factor that turns an array's stored values into reflectance, the one rule of :func:`satchain.simulate`
    and :func:`satchain.simulate_image`: ``input_scale`` when given (> 0); else 1 for floats and ``1 / (2**bits
    - 1)`` for uint8 / uint16 DN (``2**(bits - 1) - 1`` for int8 / int16); wider integers are refused without
    ``input_scale``, their width states no DN range (``np.array([[0, 200]])`` is int64: its 2**63 - 1 would make
    200 a reflectance of 2e-17).

    Examples
    --------
    >>> reflectance_gain(np.uint8), reflectance_gain(np.float32), reflectance_gain(np.int64, 1e-3)
    (0.00392156862745098, 1.0, 0.001)
    """
    from satchain.io.images import integer_scale

    if input_scale is not None:
        return check_positive("input_scale", input_scale)
    dt = np.dtype(dtype)
    if dt.kind in "iu" and dt.itemsize > 2:
        raise InputError(
            f"image: dtype {dt} states no DN range (only 8- and 16-bit integers are scaled by their range); "
            "give input_scale (1 for values that are reflectance, 1 / 4095 for 12-bit DN), or the array as float "
            "reflectance or uint8 / uint16 DN"
        )
    return integer_scale(dt)


class ArraySource:
    """A 2-D array (in memory or a memmap) as ground truth with a stated ground pixel size; its values are
    reflectance as :func:`reflectance_gain` reads them (uint8 / uint16 DN by their range, or ``input_scale``).

    Examples
    --------
    >>> src = ArraySource(np.arange(12.0).reshape(3, 4), pixel_m=0.05)
    >>> src.read(Window(1, 1, 2, 2)).tolist()
    [[5.0, 6.0], [9.0, 10.0]]
    """

    def __init__(self, array, *, pixel_m: float, input_scale: float | None = None):
        array, masked = split_mask("image", array)
        if masked is not None:
            raise InputError(
                f"image: {int(masked.sum())} pixel(s) are masked; simulate() takes no data gaps (as NaN is refused): "
                "satchain.simulate_image takes them as no data and marks the output pixels they touch invalid"
            )
        a = np.asarray(array) if not isinstance(array, np.ndarray) else array
        if a.ndim != 2:
            raise InputError(f"image: must be 2-D (rows, cols), got shape {a.shape}")
        if a.shape[0] < 1 or a.shape[1] < 1:
            raise InputError(f"image: must not be empty, got shape {a.shape}")
        if not np.issubdtype(a.dtype, np.number) or np.iscomplexobj(a):
            raise InputError(f"image: must be real numeric, got dtype {a.dtype}")
        self.array, self.gain = a, reflectance_gain(a.dtype, input_scale)
        self.pixel_m = check_positive("pixel_m", pixel_m)
        self.shape_px = (int(a.shape[0]), int(a.shape[1]))

    def read(self, window: Window) -> np.ndarray:
        return np.asarray(self.read_stored(window), dtype=np.float64)

    def read_stored(self, window: Window, *, check: bool = True) -> np.ndarray:
        """``window`` as stored (a view of the array, its own dtype: no copy; scaled by the gain, a copy, when
        that is not 1), checked finite (``check``)."""
        block = self.array[window.rows, window.cols]
        if check:
            _check_finite(block, window)
        return block if self.gain == 1.0 else block * self.gain


def _check_finite(block: np.ndarray, window: Window) -> None:
    """Refuse NaN/inf in ``block``: one pass summing it (no temporary), the element test only where the sum is
    not finite (a NaN/inf, or an overflow of large finite values)."""
    if block.dtype.kind not in "fc":
        return
    with np.errstate(over="ignore", invalid="ignore"):
        if np.isfinite(np.add.reduce(block, axis=None)):
            return
    if not np.all(np.isfinite(block)):
        raise InputError(f"image: window {tuple(window)} contains NaN/inf; ground truth must be finite")


class SceneSource:
    """A scene (:class:`satchain.scene.Scene` or :class:`satchain.scene.ImageScene`: anything with
    ``render(window, *, pixel_m)`` and ``shape_px(pixel_m)``) rendered window by window at ``pixel_m``.
    Nothing is rendered until the engine reads a window; the scene never exists in full."""

    def __init__(self, scene, *, pixel_m: float | None = None):
        self.scene = scene
        self.pixel_m = check_positive("pixel_m", scene.pixel_m if pixel_m is None else pixel_m)
        rows, cols = (int(v) for v in scene.shape_px(self.pixel_m))
        self.shape_px = (rows, cols)

    def read(self, window: Window) -> np.ndarray:
        return np.asarray(self.read_stored(window), dtype=np.float64)

    def read_stored(self, window: Window, *, check: bool = True) -> np.ndarray:
        """``window`` as the scene renders it (its own dtype; the scene checks it)."""
        return np.asarray(self.scene.render(tuple(window), pixel_m=self.pixel_m))


def as_ground_truth(obj, *, pixel_m: float | None = None, input_scale: float | None = None) -> GroundTruth:
    """An array (with ``pixel_m``; values as :func:`reflectance_gain` reads them), a scene, or a source -> a
    :class:`GroundTruth` for the engine."""
    from satchain.errors import ConfigError

    if isinstance(obj, np.ndarray):
        if pixel_m is None:
            raise ConfigError("pixel_m = None: an array ground truth needs its ground pixel size in metres")
        return ArraySource(obj, pixel_m=pixel_m, input_scale=input_scale)
    if input_scale is not None:
        raise ConfigError(f"input_scale = {input_scale!r}: applies to arrays only, not to a {type(obj).__name__}")
    if hasattr(obj, "render") and callable(getattr(obj, "shape_px", None)):
        return SceneSource(obj, pixel_m=pixel_m)
    if isinstance(obj, GroundTruth):
        if pixel_m is not None and abs(pixel_m - obj.pixel_m) > 1e-12 * obj.pixel_m:
            raise ConfigError(f"pixel_m = {pixel_m!r}: the source's pixel size is {obj.pixel_m!r}")
        return obj
    raise ConfigError(
        f"ground_truth = {type(obj).__name__}: must be an array, a scene, or a source with pixel_m, shape_px, read()"
    )


def _map_indices(start: int, length: int, n: int, rule: str) -> np.ndarray:
    i = np.arange(start, start + length)
    if rule == "periodic":
        return np.mod(i, n)
    # symmetric: ... 2 1 0 | 0 1 2 ... n-1 | n-1 n-2 ... ; period 2n
    j = np.mod(i, 2 * n)
    return np.where(j < n, j, 2 * n - 1 - j)


def _runs(start: int, length: int, n: int, rule: str) -> list[tuple[int, int, int, int]]:
    """:func:`_map_indices` as runs ``(dst, src, count, step)``: ``dst .. dst + count`` of the window are source
    indices ``src, src + step, ...`` (step +1, or -1 for a mirrored run)."""
    runs, i, end = [], start, start + length
    while i < end:
        j = i % (2 * n if rule == "symmetric" else n)
        if j < n:
            cnt, src, step = min(n - j, end - i), j, 1
        else:  # the mirrored half of the symmetric period
            cnt, src, step = min(2 * n - j, end - i), 2 * n - 1 - j, -1
        runs.append((i - start, src, cnt, step))
        i += cnt
    return runs


def index_runs(idx: np.ndarray) -> list[tuple[int, int, int, int]]:
    """``idx`` (1-D, integers) as runs ``(dst, src, count, step)``, step 1, -1 or 0 (a repeated index)."""
    runs, i, n = [], 0, len(idx)
    d = np.diff(idx).tolist()
    idx = idx.tolist()
    while i < n:
        step = d[i] if i < n - 1 and d[i] in (-1, 0, 1) else 1
        j = i + 1
        while j < n and d[j - 1] == step:
            j += 1
        runs.append((i, idx[i], j - i, step))
        i = j
    return runs


def take(array: np.ndarray, iy: np.ndarray, ix: np.ndarray, *, dtype=np.float32) -> np.ndarray:
    """``array[np.ix_(iy, ix)]`` as ``dtype``, copied by slices over the runs of the indices (mirrored or wrapped
    index maps have a few): only those elements are read (a memmap is never loaded whole)."""
    ry, rx = index_runs(np.asarray(iy)), index_runs(np.asarray(ix))
    if len(ry) * len(rx) > 256:  # many short runs: index arrays
        return np.asarray(array[np.ix_(iy, ix)], dtype=dtype)
    out = np.empty((len(iy), len(ix)), dtype=dtype)
    for dy, sy, cy, ty in ry:
        rows = _run_slice(sy, cy, ty, 0)
        for dx, sx, cx, tx in rx:
            out[dy : dy + cy, dx : dx + cx] = array[rows, _run_slice(sx, cx, tx, 0)]
    return out


def _span(runs: list[tuple[int, int, int, int]]) -> tuple[int, int]:
    """The source indices ``[lo, hi)`` that ``runs`` cover."""
    lo = min(src if step > 0 else src - cnt + 1 for _, src, cnt, step in runs)
    hi = max(src + cnt if step > 0 else src + 1 for _, src, cnt, step in runs)
    return lo, hi


def _run_slice(src: int, cnt: int, step: int, lo: int) -> slice:
    a = src - lo
    if step == 0:  # one index repeated: a length-1 slice, broadcast
        return slice(a, a + 1)
    if step > 0:
        return slice(a, a + cnt)
    return slice(a, a - cnt if a - cnt >= 0 else None, -1)


def _read(source: GroundTruth, window: Window, check: bool = True) -> np.ndarray:
    stored = getattr(source, "read_stored", None)
    return stored(window, check=check) if stored is not None else source.read(window)


class BorderedWindow:
    """``window`` of ``source`` continued beyond it by the border ``rule``, as ``dtype``, assembled on demand
    by rows: ``w[a:b]`` copies rows ``a .. b`` from the source block by slices (mirrored runs are reversed
    views; no index arrays), or is a view of an :class:`ArraySource` already of ``dtype`` when the window lies
    inside it. The source is read once; the engine transforms a tile chunk by chunk, so the whole bordered
    tile never exists. ``np.asarray(w)`` is all of it. ``check=False`` defers the NaN/inf scan of the source
    block to :meth:`require_finite`."""

    def __init__(self, source: GroundTruth, window: Window, *, rule: str, value: float = 0.0, dtype=np.float64,
                 check: bool = True):  # fmt: skip
        check_choice("border", rule, BORDER_RULES)
        self.window, self.value, self.dtype = window, float(value), np.dtype(dtype)
        self.shape = (int(window.height), int(window.width))
        self.ndim = 2
        ny, nx = source.shape_px
        (r0, h), (c0, w) = (window.row0, window.height), (window.col0, window.width)
        self.inside = r0 >= 0 and c0 >= 0 and r0 + h <= ny and c0 + w <= nx
        self.ry: Sequence[tuple[int, int | None, int, int]]
        self.rx: Sequence[tuple[int, int | None, int, int]]
        if self.inside or rule == "constant":  # fill runs (source index None) outside the source
            self.ry, self.rx = _clip_runs(r0, h, ny), _clip_runs(c0, w, nx)
            self.fill = not self.inside
        else:
            self.ry, self.rx, self.fill = _runs(r0, h, ny, rule), _runs(c0, w, nx, rule), False
        spans = [[(d, s, c, t) for d, s, c, t in runs if s is not None] for runs in (self.ry, self.rx)]
        (self.y0, y1), (self.x0, x1) = (_span(r) if r else (0, 0) for r in spans)
        empty = y1 <= self.y0 or x1 <= self.x0
        self.block = None if empty else _read(source, Window(self.y0, self.x0, y1 - self.y0, x1 - self.x0), check)
        self._whole = None
        if len(self.ry) * len(self.rx) > 64:  # a source far smaller than the window: index arrays, once
            iy = _map_indices(r0, h, ny, rule) - self.y0
            ix = _map_indices(c0, w, nx, rule) - self.x0
            assert self.block is not None  # so many runs: the source continued by a rule, read (not empty)
            self._whole = np.asarray(self.block[np.ix_(iy, ix)], dtype=self.dtype)

    def __getitem__(self, rows: slice) -> np.ndarray:
        a, b, _ = rows.indices(self.shape[0])
        if self._whole is not None:
            return self._whole[a:b]
        if self.inside:
            if self.block is None:  # an empty window (height or width 0) inside the source: nothing to read
                return np.empty((b - a, self.shape[1]), self.dtype)
            with np.errstate(over="ignore"):
                return np.asarray(self.block[a:b], dtype=self.dtype)
        out = (
            np.full((b - a, self.shape[1]), self.value, self.dtype)
            if self.fill
            else np.empty((b - a, self.shape[1]), self.dtype)
        )
        for dy, sy, cy, ty in self.ry:
            lo, hi = max(dy, a), min(dy + cy, b)
            if hi <= lo or sy is None:
                continue
            src_rows = _run_slice(sy + ty * (lo - dy), hi - lo, ty, self.y0)
            for dx, sx, cx, tx in self.rx:
                if sx is not None:
                    assert self.block is not None  # a run inside the source along both axes: the block was read
                    with np.errstate(over="ignore"):  # beyond float32: inf, refused by require_finite
                        out[lo - a : hi - a, dx : dx + cx] = self.block[src_rows, _run_slice(sx, cx, tx, self.x0)]
        return out

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        return np.asarray(self[:], dtype=dtype)

    def require_finite(self, result: np.ndarray) -> np.ndarray:
        """``result`` (computed from this window) when it is finite; else the source block's NaN/inf is reported
        (every output of a transform sums every input, so one NaN/inf in the input spoils all of it)."""
        if np.isfinite(result).all():
            return result
        if self.block is not None:  # the source's window that was read
            _check_finite(self.block, Window(self.y0, self.x0, *self.block.shape))
        read = (self.y0, self.x0, *(self.block.shape if self.block is not None else (0, 0)))
        raise InputError(f"image: window {read}: values too large for the float32 transforms (finite input, "
                         f"non-finite result); scale the ground truth")  # fmt: skip


def _clip_runs(start: int, length: int, n: int) -> list[tuple[int, int | None, int, int]]:
    """Runs of ``start .. start + length`` over ``[0, n)``: the part inside the source, fill (None) beyond."""
    lo, hi = min(max(start, 0), start + length), max(min(start + length, n), start)
    runs: list[tuple[int, int | None, int, int]] = [(0, None, lo - start, 0)] if lo > start else []
    if hi > lo:
        runs.append((lo - start, lo, hi - lo, 1))
    if start + length > max(hi, lo):
        runs.append((max(hi, lo) - start, None, start + length - max(hi, lo), 0))
    return runs


def read_with_border(
    source: GroundTruth, window: Window, *, rule: str = "symmetric", value: float = 0.0, dtype=np.float64
) -> np.ndarray:
    """Read ``window`` from ``source``; the parts outside the source follow the border ``rule``. The result is
    ``dtype``; a window inside an :class:`ArraySource` already of that dtype is a view of it (no copy)."""
    return BorderedWindow(source, window, rule=rule, value=value, dtype=dtype)[:]
