"""Pushbroom TDI imaging in time: each output row integrates the scene over its TDI window at the line of sight of
each instant (issue 20, point 2).

Conventions (README, "Pushbroom TDI motion"; :mod:`satchain.config.sections_motion`): ``t = 0`` is the start of row 0's
TDI window; row ``i`` integrates over ``[i dt, i dt + N dt]`` (``dt`` the line time, ``N`` the TDI stages). The
charge packet of row ``i`` sees, at time ``t``, the ground point

    y = i + eps t / dt + LOS_y(t),      x = j + sigma t / dt + LOS_x(t)       (detector pixels of each axis)

where ``eps`` is the ALT drift per line time (``motion.line_rate_error`` plus the Earth's along-track term) and
``sigma`` the ACT drift (the Earth's rotation, :func:`satchain.tf.pushbroom._earth_rotation`); ``LOS`` is the sum
of the ``[[motion.oscillation]]`` sinusoids, one realisation of each ``[motion.jitter_psd]`` and the
``[motion.line_of_sight]`` log (linear between its samples, 8 time samples per interval at least). With
``u = t / dt - i`` in ``[0, N]`` this is the row's own position ``i (1 + eps)`` plus the drift ``eps u`` over the
window: the image is scaled by ``1 + eps`` along-track and sheared by ``sigma`` px per row, and smeared by the
drift, exactly as :class:`satchain.tf.pushbroom.PushbroomTerms` predicts.

Exactness. The static image (all blur but these motion terms) is band-limited; a shift of the sampling position
by ``d`` multiplies each spectral basis function by ``exp(2 pi i f d)``. The output row ``i`` is therefore the
static row formed with the averages ``H_i(f) = mean over its window of exp(2 pi i f D(t))``: when only one axis
moves (or only drifts are present... on one axis) ``H_i`` multiplies that axis's sampling matrix row by row and
costs one pass; when both axes move within the window the average is taken over the time samples (``K`` times
the static cost). ``H_i`` is a sliding-window mean over one global time grid (``samples_per_line`` samples per
line time, midpoints), so the image does not depend on the tiling, and the motion realisation depends only on
the seed.

Sampling. ``samples_per_line`` is chosen so that the highest frequency of the path has at least
:data:`SAMPLES_PER_PERIOD` samples per period and every window at least :data:`MIN_WINDOW_SAMPLES`; the window
mean of a sinusoid sampled so is within 1e-4 of its integral (``tests/engine/test_timepath.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from satchain.tf.pushbroom_otf import (  # noqa: F401 (the time grid, named here as before)
    LOG_SAMPLES,
    MIN_WINDOW_SAMPLES,
    SAMPLES_PER_PERIOD,
    samples_per_line,
)

__all__ = ["MIN_WINDOW_SAMPLES", "SAMPLES_PER_PERIOD", "TimePath", "form_rows", "time_path"]

_BLOCK_BYTES = 128 * 2**20  # the sliding sums of one block of rows


@dataclass(frozen=True)
class TimePath:
    """The line of sight over the whole scan on one time grid: ``dy``, ``dx`` (detector pixels, ALT and ACT) at
    ``t_j = (j + 0.5) dt / m`` for ``j = 0 .. (rows + N) m - 1`` (``m = samples_per_line``), drifts included.
    ``moves_y`` / ``moves_x``: whether that axis moves within a window; ``drift_px``: the (ACT, ALT) drift per line
    time; ``line_of_sight``: whether there is motion besides the drifts (oscillations, jitter)."""

    line_time_s: float
    stages: int
    samples_per_line: int
    dy: np.ndarray
    dx: np.ndarray
    moves_y: bool
    moves_x: bool
    drift_px: tuple[float, float] = (0.0, 0.0)
    line_of_sight: bool = True

    @property
    def window_samples(self) -> int:
        return self.stages * self.samples_per_line

    def window(self, rows: tuple[int, int]) -> tuple[int, int]:
        """The time samples ``[a, b)`` that rows ``rows[0] .. rows[1]-1`` integrate over."""
        m = self.samples_per_line
        return rows[0] * m, (rows[1] + self.stages) * m

    def row_average(self, axis: str, rows: tuple[int, int], phase_per_px: np.ndarray) -> np.ndarray:
        """``H[i, a] = mean over row i's window of exp(2 pi i phase_per_px[a] d(t))`` for the rows ``rows``:
        ``phase_per_px`` is the spectral frequency in cycles per detector pixel of that axis (shape (n,))."""
        d = self.dy if axis == "alt" else self.dx
        a, b = self.window(rows)
        k = self.window_samples
        e = np.exp(2j * np.pi * np.outer(d[a:b], phase_per_px))
        c = np.zeros((b - a + 1, e.shape[1]), dtype=np.complex128)
        np.cumsum(e, axis=0, out=c[1:])
        del e
        m = self.samples_per_line
        starts = np.arange(rows[1] - rows[0]) * m
        return (c[starts + k] - c[starts]) / k

    def samples(self, rows: tuple[int, int], row: int) -> tuple[np.ndarray, np.ndarray]:
        """``(dy, dx)`` over the window of ``row`` (absolute row index)."""
        m = self.samples_per_line
        a = row * m
        return self.dy[a : a + self.window_samples], self.dx[a : a + self.window_samples]


def _psd_realisation(table, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One Gaussian realisation of a one-sided PSD (px^2/Hz, linear between its points) at the times ``t``: a sum
    of cosines at the frequencies ``k / T_total`` with Rayleigh amplitudes ``sqrt(S df) * chi_2`` and uniform
    phases, evaluated by an inverse FFT on the (uniform) grid."""
    n = t.size
    dt = float(t[1] - t[0]) if n > 1 else 1.0
    n_fft = 2 * n  # the realisation is periodic over 2 x the scan: no wrap-around correlation inside it
    f = np.fft.rfftfreq(n_fft, dt)
    s = np.interp(f, table.frequency_hz, table.psd_px2_per_hz, left=0.0, right=0.0)
    df = 1.0 / (n_fft * dt)
    z = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) * np.sqrt(s * df / 4.0)
    z[0] = 0.0
    x = np.fft.irfft(z * np.exp(2j * np.pi * f * t[0]), n=n_fft) * n_fft  # sum_k 2 Re(z_k e^{2 pi i f_k t})
    return x[:n]


def time_path(system, n_rows: int, *, seed: int = 0) -> TimePath | None:
    """The line-of-sight path of ``system`` over ``n_rows`` output rows (None without pushbroom motion keys).
    The jitter realisation comes from ``numpy.random.SeedSequence([seed, 20])`` (the detector noise uses
    ``seed`` itself): identical for any tiling."""
    from satchain.tf.pushbroom import PushbroomTerms

    terms = PushbroomTerms(system)
    if not terms.active:
        return None
    dt, n_st = terms.line_time_s, terms.stages
    m = samples_per_line(system, dt, n_st)
    j = np.arange((int(n_rows) + n_st) * m, dtype=np.float64)
    t = (j + 0.5) * dt / m
    sigma, eps = terms.drift_px if terms.drift_px is not None else (0.0, 0.0)
    dy, dx = eps * t / dt, sigma * t / dt
    for o in system.motion.oscillation:
        s = o.amplitude_px * np.sin(2 * np.pi * o.frequency_hz * t + math.radians(o.phase_deg))
        if o.axis == "alt":
            dy = dy + s
        else:
            dx = dx + s
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 20]))
    for table in system.motion.jitter_psd:
        r = _psd_realisation(table, t, rng)
        if table.axis == "alt":
            dy = dy + r
        else:
            dx = dx + r
    if system.motion.line_of_sight is not None:
        act, alt = system.motion.line_of_sight.at(t)
        dx, dy = dx + act, dy + alt
    moves = [bool(np.ptp(d) > 0) for d in (dy, dx)]
    los = system.motion.time_varying
    return TimePath(dt, n_st, m, dy, dx, moves[0], moves[1], (float(sigma), float(eps)), los)


def form_rows(tp: TimePath, rows: tuple[int, int], my: np.ndarray, v: np.ndarray, mx: np.ndarray, fy: np.ndarray,
              fx: np.ndarray) -> np.ndarray:  # fmt: skip
    """``Re(mean over each row's window of (my(t) v mx(t)^T))``: the static evaluation ``Re(my @ v @ mx.T)`` of
    output rows ``rows`` (``my``: rows x by sampling matrix, ``v``: by x bx band values, ``mx``: cols x bx) with
    every row's sampling positions moved along ``tp``. ``fy`` / ``fx``: the band's frequencies in cycles per
    detector pixel of each axis. Worked in blocks of rows (memory bounded)."""
    n = rows[1] - rows[0]
    out = np.empty((n, mx.shape[0]), dtype=np.float64)
    per_row = tp.samples_per_line * max(fy.size, fx.size) * 32.0
    step = max(1, int(_BLOCK_BYTES // per_row) - tp.stages)
    for a in range(0, n, step):
        b = min(n, a + step)
        r = (rows[0] + a, rows[0] + b)
        if tp.moves_y and tp.moves_x and not tp.line_of_sight:
            out[a:b] = _drifts(tp, r, my[a:b], v, mx, fy, fx)
            continue
        if tp.moves_y and tp.moves_x:
            out[a:b] = _coupled(tp, r, my[a:b], v, mx, fy, fx)
            continue
        m = my[a:b] * tp.row_average("alt", r, fy) if tp.moves_y else my[a:b]
        res = m @ v
        if tp.moves_x:
            res *= tp.row_average("act", r, fx)
        out[a:b] = np.real(res @ mx.T)
    return out


def _drifts(tp: TimePath, rows: tuple[int, int], my, v, mx, fy, fx) -> np.ndarray:
    """Drifts only, on both axes (Earth rotation, a line-rate error): ``d(t) = drift t / dt``. The window mean
    factors exactly into each row's own shift ``drift i`` and one row-independent mean over ``u = t / dt - i``,
    taken at the same time samples as the path: the static cost."""
    sx, sy = tp.drift_px
    m, k = tp.samples_per_line, tp.window_samples
    u = (np.arange(k) + 0.5) / m
    d = np.zeros((fy.size, fx.size), dtype=np.complex128)
    for uk in u:  # mean over the window of exp(2 pi i u (fy eps + fx sigma)): by x bx, K terms
        d += np.exp(2j * np.pi * uk * sy * fy)[:, None] * np.exp(2j * np.pi * uk * sx * fx)[None, :]
    d /= k
    i = np.arange(rows[0], rows[1], dtype=np.float64)
    r = (my * np.exp(2j * np.pi * np.outer(i * sy, fy))) @ (v * d)
    r *= np.exp(2j * np.pi * np.outer(i * sx, fx))
    return np.real(r @ mx.T)


def _coupled(tp: TimePath, rows: tuple[int, int], my, v, mx, fy, fx) -> np.ndarray:
    """Both axes move within the window: the mean over the time samples of each row (K x the static cost)."""
    out = np.empty((rows[1] - rows[0], mx.shape[0]), dtype=np.float64)
    for i in range(rows[1] - rows[0]):
        dy, dx = tp.samples(rows, rows[0] + i)
        r = (np.exp(2j * np.pi * np.outer(dy, fy)) * my[i][None, :]) @ v
        r *= np.exp(2j * np.pi * np.outer(dx, fx))
        out[i] = np.real(r.mean(axis=0) @ mx.T)
    return out
