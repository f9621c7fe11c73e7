"""Yaw steering in the simulation (issue 20): the detector line turned by ``gamma`` so that its columns follow the
ground's motion relative to the satellite (``orbit.yaw_steering``, :func:`satchain.tf.pushbroom._earth_rotation`).

The whole system (optics, detector footprints, TDI smear, jitter) lies in the detector's frame, so a turned
detector sees the ground turned the other way: the engine forms the static image of the ground truth rotated
about the centre of the output grid,

    B'(q) = B(P + M (q - P)),      M = [[cos g, sin g], [-sin g, cos g]]      (x = column, y = row),

which is the map :meth:`satchain.tf.pushbroom.PushbroomTerms.image_affine` describes (row ``i`` of the image lies
along the ground direction ``(sin g, cos g)``), and its rows then move along the columns only (the ALT scale of
the relative speed, in time). The rotation is applied to the coarse frame (the band-limited ground truth) as three
shears, ``M = Sx(tan(g/2)) Sy(-sin g) Sx(tan(g/2))``, each an exact Fourier shift of every row (column) of the
frame. The band stays below the coarse Nyquist frequency through the shears (checked), and the frame is widened by
the rotation's reach so that the shears' wrap-around lies in its far margin, as the frame's own period does.

The rotated frame is made once, after stage 1, by bands of rows and columns (:func:`rotate_into`): in memory, or
for a streamed simulation in a disk-backed array beside the coarse grid; stage 2 then reads it as it reads the
frame (whole, by tiles, or for the far field), so yaw steering streams like every other case.
"""

from __future__ import annotations

import math

import numpy as np

from satchain.errors import ConfigError

__all__ = [
    "check_band",
    "grid_origin_m",
    "image_affine",
    "rotate_frame",
    "rotate_into",
    "rotated_frame",
    "rotated_window",
    "yaw_margin",
    "yaw_rotation_deg",
]

_BAND_BYTES = 64 * 2**20  # the transform of one band of rows or columns


def yaw_rotation_deg(system) -> float:
    """The detector's yaw ``gamma`` (degrees) under ``orbit.yaw_steering`` with Earth rotation, else 0."""
    orb = system.orbit
    if not (orb.yaw_steering and orb.earth_rotation):
        return 0.0
    from satchain.tf.pushbroom import _earth_rotation

    return float(_earth_rotation(system)["rotation_deg"])


def yaw_margin(n_coarse: tuple[int, int], angle_deg: float) -> int:
    """Coarse samples to add on every side of the frame so that the rotated frame's corners stay inside it."""
    if angle_deg == 0:
        return 0
    half = 0.5 * math.hypot(*n_coarse)
    return int(math.ceil(half * abs(math.sin(math.radians(angle_deg))) * 1.05)) + 8


def check_band(f_band: float, f_stop: float, angle_deg: float) -> None:
    """The shears spread the band ``|f| <= f_band`` (cycles per coarse sample) by at most the factor ``R`` of the
    three passes (``1 + t``, ``1 + s + t s``, ``1 + 2 t + t s + t^2 s``; ``t = tan(g/2)``, ``s = sin g``): it must
    stay below Nyquist (0.5), and what the shears alias out of the stopband (up to ``f_stop``) must land above the
    band, where the OTF is zero."""
    g = math.radians(angle_deg)
    t, s = abs(math.tan(g / 2)), abs(math.sin(g))
    r = max(1 + t, 1 + s + t * s, 1 + 2 * t + t * s + t * t * s)
    reach = f_band * r
    folded = 1.0 - f_stop * r  # the lowest frequency a stopband alias lands on
    if reach >= 0.5 or folded <= f_band:
        raise ConfigError(
            f"orbit.yaw_steering: a yaw of {angle_deg:.3g} deg spreads the band ({f_band:.3g} cycles per coarse "
            "sample) past the coarse grid's Nyquist frequency; this geometry cannot be simulated exactly"
        )


def _shear(a: np.ndarray, axis: int, shift: np.ndarray, workers: int | None) -> np.ndarray:
    """``out[..] = a[.. + shift]`` along ``axis`` (periodic, band-limited), ``shift`` one value per line."""
    import scipy.fft as sfft

    n = a.shape[axis]
    f = sfft.rfft(a, axis=axis, workers=workers)
    k = np.fft.rfftfreq(n)
    ph = np.exp(2j * np.pi * np.outer(shift, k)).astype(f.dtype)  # lines x frequencies
    if n % 2 == 0:
        ph[:, -1] = 0.0  # the Nyquist term of a real line cannot be shifted; it lies in the stopband
    f *= ph if axis == 1 else ph.T
    return sfft.irfft(f, n=n, axis=axis, workers=workers).astype(a.dtype, copy=False)


def rotate_frame(frame: np.ndarray, angle_deg: float, pivot: tuple[float, float], *, workers=None) -> np.ndarray:
    """``B'(q) = B(P + M (q - P))`` (module docstring) of the periodic band-limited ``frame``; ``pivot = (row, col)``
    in frame samples."""
    out = np.empty(frame.shape, dtype=np.float32)
    rotate_into(lambda a, h: frame[a : a + h], frame.shape, out, angle_deg, pivot, workers=workers)
    return out


def rotate_into(read_rows, shape: tuple[int, int], out: np.ndarray, angle_deg: float, pivot: tuple[float, float],
                *, workers=None, band_bytes: float = _BAND_BYTES) -> None:  # fmt: skip
    """:func:`rotate_frame` out of core: ``read_rows(a, h)`` gives frame rows ``a .. a+h-1``, the result goes into
    ``out`` (``shape``, float32; a disk-backed array works): row bands for the two x-shears, column bands for the
    y-shear, each band at most ``band_bytes`` of transform (the frame is never read whole)."""
    from satchain.engine.sources import release_pages

    g = math.radians(angle_deg)
    t, s = math.tan(g / 2), -math.sin(g)
    py, px = pivot
    ly, lx = shape
    h = max(1, int(band_bytes // (16 * lx)))
    for a in range(0, ly, h):  # B1(x, y) = B(x + t (y - py), y)
        blk = np.asarray(read_rows(a, min(h, ly - a)), dtype=np.float32)
        out[a : a + blk.shape[0]] = _shear(blk, 1, t * (np.arange(a, a + blk.shape[0]) - py), workers)
        release_pages(out)
    w = max(1, int(band_bytes // (16 * ly)))
    for c in range(0, lx, w):  # B2(x, y) = B1(x, y + s (x - px))
        blk = np.asarray(out[:, c : c + w], dtype=np.float32)
        out[:, c : c + blk.shape[1]] = _shear(blk, 0, s * (np.arange(c, c + blk.shape[1]) - px), workers)
        release_pages(out)
    for a in range(0, ly, h):  # B3 = B2 sheared as B1
        blk = np.asarray(out[a : a + h], dtype=np.float32)
        out[a : a + blk.shape[0]] = _shear(blk, 1, t * (np.arange(a, a + blk.shape[0]) - py), workers)
        release_pages(out)


def rotated_frame(sim, coarse: np.ndarray) -> np.ndarray:
    """The coarse frame of ``coarse`` rotated about the output grid's centre, made once per coarse grid (kept in
    ``sim._yaw_cache``): in memory, or into ``sim.yaw_store(shape)`` when a streamed caller set it (a disk-backed
    array beside the coarse grid, :func:`satchain.engine.stream.coarse_store`)."""
    if sim._yaw_cache is not None and sim._yaw_cache[0] is coarse:
        return sim._yaw_cache[1]
    check_band(sim.f_pass * sim.D, sim.f_stop * sim.D, sim.yaw_deg)  # the whole pass band (bands share it)
    from satchain.tf.pushbroom import yaw_pivot_m

    (ey, ex), (ly, lx) = sim.frame_ext, sim.frame_shape
    a = sim.input_pixel_m
    x_m, y_m = yaw_pivot_m(sim.output_shape, (sim.xs.k * a, sim.ys.k * a), grid_origin_m(sim))  # image_affine's
    pivot = [y_m / a / sim.D - 0.5 + ey, x_m / a / sim.D - 0.5 + ex]  # in frame samples
    store = getattr(sim, "yaw_store", None)
    out = np.empty((ly, lx), dtype=np.float32) if store is None else store((ly, lx))
    sim._yaw_cache = None  # a failed rotation leaves no stale frame
    rotate_into(lambda a, h: sim._frame_window(coarse, (a - ey, -ex), (h, lx), rotated=False), (ly, lx), out,
                sim.yaw_deg, (pivot[0], pivot[1]), workers=sim.params.workers)  # fmt: skip
    sim._yaw_cache = (coarse, out)
    return out


def grid_origin_m(sim) -> tuple[float, float]:
    """The detector grid's corner on the ground truth of simulator ``sim``, ``(x, y)`` m (its
    ``SimParams.phase_px`` in metres)."""
    return sim.xs.phase_px * sim.input_pixel_m, sim.ys.phase_px * sim.input_pixel_m


def image_affine(sim):
    """The image's mean map from ground-truth metres to its pixels (``affine.Affine``, pixel centres at integers)
    for simulator ``sim``: :meth:`satchain.tf.pushbroom.PushbroomTerms.image_affine` of its grid (shape, corner
    :func:`grid_origin_m`), whose yaw pivot (:func:`satchain.tf.pushbroom.yaw_pivot_m`) is the one
    :func:`rotated_frame` turns the ground about."""
    from satchain.tf.pushbroom import PushbroomTerms

    return PushbroomTerms(sim.system).image_affine(sim.output_shape, origin_m=grid_origin_m(sim))


def rotated_window(sim, coarse: np.ndarray, start: tuple[int, int], shape: tuple[int, int]) -> np.ndarray:
    """Samples ``start .. start + shape`` (ground-truth coarse coordinates) of the rotated frame, periodically
    over it, as float32 (copied by slices, :func:`satchain.engine.sources.take`)."""
    from satchain.engine.sources import release_pages, take

    frame = rotated_frame(sim, coarse)
    iy, ix = (np.mod(np.arange(a, a + n) + e, m) for a, n, e, m in
              zip(start, shape, sim.frame_ext, sim.frame_shape, strict=True))  # fmt: skip
    out = take(frame, iy, ix)
    release_pages(frame)
    return out
