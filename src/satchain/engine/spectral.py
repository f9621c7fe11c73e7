"""Band-limited spectral image formation.

The optical OTF is exactly zero beyond the diffraction cutoff ``f_c``, so of the ground truth's spectrum only
the band ``|f| <= f_c`` reaches the detector. The engine exploits that twice:

1. **Decimation** (per fine tile): a smooth low-pass ``G`` that is exactly 1 on the optical band and exactly 0
   beyond ``f_stop < 1/(2D)`` is applied, and the tile is sampled at the centres of its ``D x D`` blocks --
   without aliasing, because nothing above ``1/(2D)`` is left. ``G`` is C-infinity, so its kernel is short
   (``~11 / (f_stop - f_c)`` input pixels to 1e-5) and tiles need only that margin; since ``G = 1`` where ``OTF != 0``,
   ``OTF * G = OTF`` and nothing is lost.
2. **Image formation** (on the coarse frame): the OTF multiplies the band of the coarse frame's DFT and the
   detector's footprint averaging is applied in frequency; the result is evaluated *at the output pixels*
   either by folding the band onto the output grid's DFT (integer GSD / input-pixel ratio: an inverse FFT of
   output size) or by a matrix DFT (any ratio). No inverse transform on the fine grid is ever done.

Transforms are real FFTs along x (columns) and complex FFTs along y (rows) of the kept columns only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.fft as sfft

from satchain.engine.tiling import footprint_weights

if TYPE_CHECKING:
    from satchain.engine.sources import BorderedWindow

__all__ = [
    "BandSpectrum",
    "band_index",
    "decimate_tile",
    "fold_onto_grid",
    "footprint_transfer",
    "lowpass",
    "sampling_matrix",
    "tile_band_spectrum",
]

#: Kernel half-length of :func:`lowpass` in units of 1 / (f_stop - f_pass): the kernel's L1 norm beyond it
#: is < 1e-5 (measured), an order below the engine's 1e-4 accuracy target.
LOWPASS_SUPPORT = 11.0
_ROW_CHUNK_PX = 1 << 20  # pixels per chunk of rows transformed at once in tile_band_spectrum


def band_index(n: int, f_cut_cy_per_px: float) -> int:
    """Largest DFT index ``m`` with ``m / n <= f_cut`` (capped at the Nyquist index ``n // 2``)."""
    return int(min(np.floor(f_cut_cy_per_px * n + 1e-9), n // 2))


def lowpass(f_abs: np.ndarray, f_pass: float, f_stop: float) -> np.ndarray:
    """1 for ``|f| <= f_pass``, 0 for ``|f| >= f_stop``, and a C-infinity step between
    (``psi(t) = e^(-1/t) / (e^(-1/t) + e^(-1/(1-t)))``), so the kernel decays faster than any power."""
    t = np.clip((np.abs(f_abs) - f_pass) / (f_stop - f_pass), 0.0, 1.0)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        a = np.where(t > 0, np.exp(-1.0 / np.where(t > 0, t, 1.0)), 0.0)
        b = np.where(t < 1, np.exp(-1.0 / np.where(t < 1, 1.0 - t, 1.0)), 0.0)
    return 1.0 - a / (a + b)


class BandSpectrum:
    """The low-frequency block of a 2-D DFT.

    ``values[a, b]`` is ``DFT[my[a], mx[b]]``: ``my`` signed row frequencies (0..By, -By..-1), ``mx`` the
    non-negative column frequencies 0..Bx of the real FFT; ``cx`` the Hermitian weights of those columns
    (1 for 0 and the Nyquist column, else 2), so a real signal is ``Re(sum cx * values * e^(...)) / (ny nx)``.
    """

    def __init__(self, values: np.ndarray, my: np.ndarray, mx: np.ndarray, shape: tuple[int, int]):
        self.values, self.my, self.mx, self.shape = values, my, mx, shape
        nx = shape[1]
        self.cx = np.where((mx == 0) | ((nx % 2 == 0) & (mx == nx // 2)), 1.0, 2.0)

    def restrict(self, *, by: int, bx: int) -> BandSpectrum:
        """The block ``|my| <= by``, ``0 <= mx <= bx`` of this one (which must hold it): exactly what
        :func:`tile_band_spectrum` gives for that band (the same values, row order and ``my``; a view when it is
        the whole of this one, else a copy)."""
        ny = self.shape[0]
        whole_rows = 2 * by + 1 >= ny
        have_by = int(np.max(np.abs(self.my))) if self.my.size else 0
        if bx > int(self.mx[-1]) or (not whole_rows and by > have_by) or (whole_rows and self.my.size < ny):
            raise ValueError(f"restrict(by={by}, bx={bx}): outside this spectrum's band (by {have_by}, "
                             f"bx {int(self.mx[-1])})")  # fmt: skip
        if whole_rows:
            rows = np.argsort(np.mod(self.my, ny), kind="stable")  # tile_band_spectrum's order: 0..ny-1 as fftfreq
            if np.array_equal(rows, np.arange(ny)) and bx == int(self.mx[-1]):
                return self
            return BandSpectrum(self.values[rows, : bx + 1], self.my[rows], self.mx[: bx + 1], self.shape)
        keep = np.concatenate([np.flatnonzero((self.my >= 0) & (self.my <= by)),
                               np.flatnonzero((self.my < 0) & (self.my >= -by))])  # fmt: skip
        keep = keep[np.argsort(np.where(self.my[keep] >= 0, self.my[keep], 2 * ny + self.my[keep]), kind="stable")]
        if keep.size == self.my.size and bx == int(self.mx[-1]):
            return self
        return BandSpectrum(self.values[keep, : bx + 1], self.my[keep], self.mx[: bx + 1], self.shape)


def tile_band_spectrum(tile: np.ndarray | BorderedWindow, *, by: int, bx: int, workers: int = 1) -> BandSpectrum:
    """DFT of ``tile`` restricted to ``|my| <= by``, ``0 <= mx <= bx``."""
    ny, nx = tile.shape
    # real FFTs of row chunks, keeping only the band's columns (a small, contiguous array for the column FFTs)
    x = np.empty((ny, bx + 1), dtype=np.result_type(tile.dtype, np.complex64))
    step = max(1, _ROW_CHUNK_PX // max(nx, 1))
    for r in range(0, ny, step):
        x[r : r + step] = sfft.rfft(tile[r : r + step], axis=1, workers=workers)[:, : bx + 1]
    y = sfft.fft(x, axis=0, workers=workers, overwrite_x=True)
    if 2 * by + 1 >= ny:
        return BandSpectrum(y, np.fft.fftfreq(ny, 1.0 / ny).round().astype(np.int64), np.arange(bx + 1), (ny, nx))
    my = np.concatenate([np.arange(by + 1), np.arange(-by, 0)])
    vals = np.concatenate([y[: by + 1], y[ny - by :]], axis=0)
    return BandSpectrum(vals, my, np.arange(bx + 1), (ny, nx))


def decimate_tile(
    tile: np.ndarray | BorderedWindow, *, D: int, f_pass: float, f_stop: float, workers: int = 1
) -> np.ndarray:
    """Low-pass ``tile`` with :func:`lowpass` and sample it at the centres of its ``D x D`` blocks (input pixel
    ``D j + (D - 1) / 2``), so that mirroring coarse samples about a block boundary is mirroring the input.

    ``tile``'s sides must be multiples of ``D`` and ``f_stop < 1 / (2 D)``; the result is exact (no aliasing)
    for the periodic tile."""
    ny, nx = tile.shape
    if D == 1:
        return np.asarray(tile, dtype=np.float32)
    cy, cx = ny // D, nx // D
    spec = tile_band_spectrum(tile, by=band_index(ny, f_stop), bx=band_index(nx, f_stop), workers=workers)
    c = (D - 1) / 2.0  # block centre: a phase ramp moves the samples there
    gy = lowpass(spec.my / ny, f_pass, f_stop) * np.exp(2j * np.pi * spec.my * c / ny) / (D * D)
    gx = lowpass(spec.mx / nx, f_pass, f_stop) * np.exp(2j * np.pi * spec.mx * c / nx)
    vals = spec.values
    with np.errstate(invalid="ignore", over="ignore"):  # a NaN/inf input spoils the result: the caller checks it
        vals *= gy[:, None].astype(vals.dtype)
        vals *= gx[None, :].astype(vals.dtype)
    coarse = np.zeros((cy, cx // 2 + 1), dtype=np.complex64)
    coarse[np.mod(spec.my, cy)[:, None], spec.mx[None, :]] = vals
    out = sfft.irfft(sfft.ifft(coarse, axis=0, workers=workers, overwrite_x=True), n=cx, axis=1, workers=workers)
    return np.asarray(out, dtype=np.float32)


def footprint_transfer(m: np.ndarray, *, centre: float, width_px: float, n_total: int) -> np.ndarray:
    """``A(m) = sum_n w(n) exp(2 pi i m n / n_total)`` for the footprint of one output pixel centred at
    ``centre`` (input pixels, frame coordinates): footprint averaging and the position of that pixel, in
    frequency."""
    idx, w = footprint_weights(np.array([centre]), width_px, 0)
    ph = np.exp(2j * np.pi * np.outer(m, idx[0]) / n_total)
    return ph @ w[0]


def fold_onto_grid(
    values: np.ndarray, my: np.ndarray, mx: np.ndarray, cx: np.ndarray, n_out: tuple[int, int]
) -> np.ndarray:
    """Sample a band-limited real signal on an output grid that divides the frame: fold the (Hermitian-half)
    spectrum onto the output DFT grid and inverse-transform. ``values`` must already contain the phase of
    the output grid's first sample; returns ``Re(sum values e^{2 pi i (my i / Ny + mx j / Nx)})``."""
    noy, nox = n_out
    vy = _fold(values, my, noy, axis=0)
    vy *= cx[None, :]  # the Hermitian weights, after the rows' fold (fewer rows)
    v = _fold(vy, mx, nox, axis=1)
    return np.real(sfft.ifft2(v, overwrite_x=True)) * (noy * nox)


def _fold(values: np.ndarray, m: np.ndarray, n: int, *, axis: int) -> np.ndarray:
    """``out[r] = sum of values[a] over m[a] = r (mod n)`` along ``axis`` (complex128). ``m`` holds consecutive
    integers in any order (the DFT's): each run of consecutive ``m`` is added slice by slice, the runs in
    increasing ``m`` (every output sums its terms in increasing ``m``); no copy of ``values`` is made."""
    m = np.asarray(m)
    shape = list(values.shape)
    shape[axis] = n
    out = np.zeros(shape, dtype=np.complex128)
    if m.size and np.any(np.diff(np.sort(m)) != 1):  # not consecutive: the general (slower) scatter-add
        np.add.at(np.moveaxis(out, axis, 0), np.mod(m, n), np.moveaxis(values, axis, 0))
        return out
    cut = np.flatnonzero(np.diff(m) != 1) + 1
    starts, ends = np.concatenate([[0], cut]), np.concatenate([cut, [m.size]])
    runs = sorted(zip(starts, ends, strict=True), key=lambda se: m[se[0]])
    src, dst = [slice(None)] * values.ndim, [slice(None)] * values.ndim
    for a, end in runs:
        while a < end:
            r = int(m[a]) % n
            length = min(int(end - a), n - r)
            src[axis], dst[axis] = slice(a, a + length), slice(r, r + length)
            out[tuple(dst)] += values[tuple(src)]
            a += length
    return out


def sampling_matrix(centres: np.ndarray, width_px: float, n0: int, n: int, m: np.ndarray) -> np.ndarray:
    """``M[i, a] = sum_n w_i(n) exp(2 pi i m_a (n - n0) / n)``: footprint averaging of a band-limited frame
    signal, evaluated from its DFT coefficients ``m`` (frame origin at input pixel ``n0``, ``n`` input
    pixels long). Any footprint width and position. A footprint's pixels are consecutive, so the sum is a
    polynomial in ``exp(2 pi i m / n)`` (Horner's rule, once when every footprint has the same weights) times
    the phase of its first pixel: one exponential per element instead of one per footprint pixel."""
    idx, w = footprint_weights(centres, width_px, n0)
    m = np.asarray(m)
    r = np.exp(2j * np.pi * m / n)
    if w.shape[0] > 1 and not np.any(w != w[:1]):  # every footprint alike (an integer ratio): one polynomial
        w = w[:1]
    acc = np.broadcast_to(w[:, -1, None], (w.shape[0], m.size)).astype(np.complex128)
    for k in range(idx.shape[1] - 2, -1, -1):
        acc *= r[None, :]
        acc += w[:, k, None]
    if np.issubdtype(m.dtype, np.integer):  # the first pixel's phase reduced exactly in integers
        turns = np.mod(np.outer(idx[:, 0], m), n) / n
    else:
        turns = np.outer(idx[:, 0], m) / n
    return acc * np.exp(2j * np.pi * turns)
