"""An independent full-frame reference of the image chain, written for the tests.

It shares nothing with :mod:`satchain.engine` but the system OTF itself: the whole input is transformed
with ``numpy.fft.rfft2``, multiplied by ``SystemOTF(system)(fx, fy, exclude=("detector",))`` at the input
grid's frequencies (converted to focal-plane cy/mm with :mod:`satchain.units`), transformed back with
``irfft2`` (a periodic convolution), and every detector footprint is then averaged with overlap weights
computed here from the geometry contract: output pixel ``i`` along an axis is centred at
``phase + (i + 1/2) k`` and integrates the input over ``[c - w/2, c + w/2)``, ``w = k * active / pitch``,
input pixel ``n`` covering ``[n, n + 1)``.
"""

from __future__ import annotations

import math

import numpy as np

from satchain import units
from satchain.config.system import ImagingSystem
from satchain.tf.budget import SystemOTF


def overlap_matrix(n_input: int, *, k: float, fill: float, phase_px: float, n_output: int) -> np.ndarray:
    """``W[i, n]``: the fraction of output pixel ``i``'s active footprint covered by input pixel ``n``."""
    centre = phase_px + (np.arange(n_output) + 0.5) * k
    half = k * fill / 2
    n = np.arange(n_input)
    lo = np.maximum(n[None, :], (centre - half)[:, None])
    hi = np.minimum(n[None, :] + 1.0, (centre + half)[:, None])
    return np.clip(hi - lo, 0.0, None) / (k * fill)


def cy_per_input_px_to_cy_per_mm(system: ImagingSystem, pixel_m: float) -> float:
    """Focal-plane cy/mm of one cycle per input pixel."""
    f = units.ground_to_focal_cy_per_mm(
        1.0 / pixel_m, focal_length_m=system.focal_length_m, range_m=system.orbit.range_m
    )
    return float(f)


def optical_filter(
    image: np.ndarray,
    system: ImagingSystem,
    pixel_m: float,
    *,
    conjugate: bool = False,
    otf: SystemOTF | None = None,
) -> np.ndarray:
    """Periodic convolution of ``image`` with the system PSF without the detector aperture.

    The OTF is evaluated only inside the box ``|f| <= 1.001 f_c`` (it is exactly 0 beyond the diffraction
    cutoff ``f_c = 1 / (lambda_min F#)``), which keeps the reference affordable on large frames.
    ``conjugate`` flips the PSF (used to show a test can tell orientation apart); ``otf`` is a prebuilt
    ``SystemOTF(system)`` (it saves the pupil FFT of aberrated systems).
    """
    ny, nx = image.shape
    scale = cy_per_input_px_to_cy_per_mm(system, pixel_m)
    f_c = float(np.max(system.optical_cutoff_cy_per_mm)) * 1.001 / scale  # cycles per input pixel
    by, bx = min(math.ceil(f_c * ny), ny // 2), min(math.ceil(f_c * nx), nx // 2)
    spec = np.fft.rfft2(image)
    rows = np.r_[0 : by + 1, ny - by : ny] if 2 * by + 1 < ny else np.arange(ny)
    fy = np.fft.fftfreq(ny)[rows][:, None] * scale
    fx = np.fft.rfftfreq(nx)[: bx + 1][None, :] * scale
    h = (SystemOTF(system) if otf is None else otf)(fx, fy, exclude=("detector",))
    if conjugate:
        h = np.conj(h)
    out = np.zeros_like(spec)
    out[rows[:, None], np.arange(bx + 1)[None, :]] = spec[rows][:, : bx + 1] * h
    return np.fft.irfft2(out, s=(ny, nx))


def reference_image(
    image: np.ndarray,
    system: ImagingSystem,
    pixel_m: float,
    *,
    output_shape: tuple[int, int],
    phase_px: tuple[float, float] = (0.0, 0.0),
    pad_px: tuple[int, int] = (0, 0),
    pad_mode: str = "wrap",
    pad_value: float = 0.0,
    conjugate: bool = False,
    otf: SystemOTF | None = None,
) -> np.ndarray:
    """Full-frame reference output: optionally pad the input (``np.pad`` mode) by ``pad_px`` (rows, cols)
    on every side, filter the whole frame periodically, and average the detector footprints."""
    kw = {"constant_values": pad_value} if pad_mode == "constant" else {}
    py, px = pad_px
    frame = np.pad(image, ((py, py), (px, px)), mode=pad_mode, **kw) if (py or px) else image
    filtered = optical_filter(frame, system, pixel_m, conjugate=conjugate, otf=otf)
    det = system.detector
    wy = overlap_matrix(
        frame.shape[0],
        k=system.gsd_alt_m / pixel_m,
        fill=det.active_width_y_m / det.pitch_y_m,
        phase_px=phase_px[0] + py,
        n_output=output_shape[0],
    )
    wx = overlap_matrix(
        frame.shape[1],
        k=system.gsd_act_m / pixel_m,
        fill=det.active_width_x_m / det.pitch_x_m,
        phase_px=phase_px[1] + px,
        n_output=output_shape[1],
    )
    return wy @ filtered @ wx.T


def make_scene(shape: tuple[int, int], rng: np.random.Generator, *, rectangles: int = 20) -> np.ndarray:
    """Uniform noise in [0.1, 0.9] (every frequency) with random rectangles (edges) on top."""
    img = rng.uniform(0.1, 0.9, shape)
    ny, nx = shape
    for _ in range(rectangles):
        h, w = rng.integers(5, max(6, ny // 4)), rng.integers(5, max(6, nx // 4))
        y0, x0 = rng.integers(0, ny - h), rng.integers(0, nx - w)
        img[y0 : y0 + h, x0 : x0 + w] = rng.uniform(0.1, 0.9)
    return img
