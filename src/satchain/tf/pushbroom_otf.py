"""The exposure-averaged motion transfer functions of a pushbroom TDI window, as pure functions of frequency
(oscillation, jitter PSD, drift, a line-of-sight log), and the time grid on which the line of sight is sampled.

:mod:`satchain.tf.pushbroom` (which re-exports these and explains them) assembles them into a system's
:class:`~satchain.tf.pushbroom.PushbroomTerms`; :mod:`satchain.tf.pushbroom_roi` takes them over an edge's rows;
:mod:`satchain.engine.timepath` forms the image on the same time grid (:func:`samples_per_line`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from satchain._validate import as_float_array, check_range
from satchain.errors import ConfigError

__all__ = [
    "LOG_SAMPLES",
    "MIN_WINDOW_SAMPLES",
    "SAMPLES_PER_PERIOD",
    "PSDWindow",
    "drift_otf",
    "jitter_psd_otf",
    "log_otf",
    "log_windows",
    "oscillation_displacement_px",
    "oscillation_otf",
    "psd_window",
    "samples_per_line",
    "window_means",
]

#: the time grid (:func:`samples_per_line`): samples per period of the path's highest frequency, ...
SAMPLES_PER_PERIOD = 24
LOG_SAMPLES = 8  # time samples per interval of a [motion.line_of_sight] log
MIN_WINDOW_SAMPLES = 32
_MAX_SAMPLES_PER_LINE = 4096


def samples_per_line(system, line_time_s: float, stages: int) -> int:
    """Time samples per line time of the line-of-sight grid: every period of the path's highest frequency
    :data:`SAMPLES_PER_PERIOD` times, every TDI window :data:`MIN_WINDOW_SAMPLES` times, every interval of a
    ``[motion.line_of_sight]`` log :data:`LOG_SAMPLES` times (at most 4096)."""
    mot = system.motion
    f_top = max([o.frequency_hz for o in mot.oscillation] + [t.frequency_hz[-1] for t in mot.jitter_psd] + [0.0])
    m = max(math.ceil(SAMPLES_PER_PERIOD * f_top * line_time_s), math.ceil(MIN_WINDOW_SAMPLES / stages), 1)
    if mot.line_of_sight is not None:  # a log, linear between its samples: >= LOG_SAMPLES per interval
        step = float(np.min(np.diff(mot.line_of_sight.time_s)))
        m = max(m, math.ceil(LOG_SAMPLES * line_time_s / step))
    return int(min(m, _MAX_SAMPLES_PER_LINE))


_GL8 = np.polynomial.legendre.leggauss(8)


def _series_length(a_max: float) -> int:
    """Terms of a Bessel series in ``J_k(a)``, ``a <= a_max``: ``|J_k(a)| < 1e-16`` past ``a + 10 a^(1/3) + 20``."""
    return int(math.ceil(a_max + 10.0 * a_max ** (1.0 / 3.0) + 20.0))


def oscillation_otf(nu_cy_per_px, *, amplitude_px: float, cycles_per_window: float, phase_mid_rad=None) -> np.ndarray:
    """Exposure-averaged OTF of a sinusoidal line-of-sight motion about each row's window mean.

    Parameters
    ----------
    nu_cy_per_px : array_like
        Spatial frequency along the motion's axis, cycles per pixel.
    amplitude_px : float
        Zero-to-peak amplitude ``A``.
    cycles_per_window : float
        ``c = f T``: cycles of the oscillation in one TDI window.
    phase_mid_rad : float, optional
        The phase ``psi`` at the middle of the window of one row: that row's OTF (complex), ``exp(i b sin psi)
        sum_k J_k(a) exp(-i k psi) sinc(k c)``. Default: the expectation over a uniform ``psi`` (real), the
        phase-averaged exact form ``J0(a) J0(b) + 2 sum_{k>=1} J_k(a) J_k(b) sinc(k c)``.

    Examples
    --------
    >>> from scipy.special import j0
    >>> round(float(oscillation_otf(0.5, amplitude_px=0.5, cycles_per_window=5.0)), 6), round(float(j0(np.pi / 2)), 6)
    (0.472001, 0.472001)
    """
    nu = as_float_array("nu_cy_per_px", nu_cy_per_px)
    amp = check_range("amplitude_px", amplitude_px, 0, None)
    c = check_range("cycles_per_window", cycles_per_window, 0, None)
    a = 2.0 * np.pi * np.abs(nu) * amp
    if a.size == 0 or amp == 0:
        return np.ones_like(a) if phase_mid_rad is None else np.ones_like(a, dtype=complex)
    b = a * np.sinc(c)
    out = np.empty(a.shape, dtype=float if phase_mid_rad is None else complex)
    flat_a, flat_b, flat_o = a.ravel(), b.ravel(), out.reshape(-1)
    k_max = _series_length(float(flat_a.max()))
    chunk = max(1, 2_000_000 // (k_max + 1))
    for lo in range(0, flat_a.size, chunk):
        aa, bb = flat_a[lo : lo + chunk, None], flat_b[lo : lo + chunk, None]
        if phase_mid_rad is None:
            k = np.arange(k_max + 1)
            w = np.where(k == 0, 1.0, 2.0) * np.sinc(k * c)
            flat_o[lo : lo + chunk] = np.sum(w * special.jv(k, aa) * special.jv(k, bb), axis=1)
        else:
            psi = float(phase_mid_rad)
            k = np.arange(-k_max, k_max + 1)
            s = np.sum(special.jv(k, aa) * np.exp(-1j * k * psi) * np.sinc(k * c), axis=1)
            flat_o[lo : lo + chunk] = np.exp(1j * bb[:, 0] * math.sin(psi)) * s
    return out


def oscillation_displacement_px(
    amplitude_px: float, cycles_per_window: float, *, cycles_per_line: float
) -> dict[str, float]:
    """Geometry of an oscillation: the rows' displacement ``d_i = A sinc(c) sin(psi_i)`` (``psi_i`` the phase at
    row i's mid-window, advancing ``2 pi f dt`` a row) -- its amplitude, rms and row-to-row rms.

    Examples
    --------
    >>> oscillation_displacement_px(2.0, 0.0, cycles_per_line=0.25)["amplitude_px"]
    2.0
    """
    amp = abs(amplitude_px * float(np.sinc(cycles_per_window)))
    step = 2.0 * abs(math.sin(math.pi * cycles_per_line))
    return {"amplitude_px": amp, "rms_px": amp / math.sqrt(2.0), "line_to_line_rms_px": amp * step / math.sqrt(2.0)}


@dataclass(frozen=True)
class PSDWindow:
    """A jitter PSD seen through the TDI window: the variance ``v(s)`` of the motion about the window mean at the
    quadrature offsets ``s`` (``weights`` sum to 1 over the half window), and the scalar variances (px^2)."""

    s_s: np.ndarray
    weights: np.ndarray
    variance_about_mean_px2: np.ndarray
    variance_px2: float
    blur_variance_px2: float
    displacement_variance_px2: float
    line_to_line_variance_px2: float

    def __add__(self, other: PSDWindow) -> PSDWindow:
        """Two independent motions on one axis (same window): the variances add."""
        if self.s_s.shape != other.s_s.shape or not np.allclose(self.s_s, other.s_s):
            raise ConfigError("PSDWindow: can only add windows on the same quadrature nodes")
        return PSDWindow(
            self.s_s,
            self.weights,
            self.variance_about_mean_px2 + other.variance_about_mean_px2,
            self.variance_px2 + other.variance_px2,
            self.blur_variance_px2 + other.blur_variance_px2,
            self.displacement_variance_px2 + other.displacement_variance_px2,
            self.line_to_line_variance_px2 + other.line_to_line_variance_px2,
        )


def _frequency_nodes(f_hz: np.ndarray, window_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Composite 8-point Gauss-Legendre nodes and weights over each segment of the PSD table, subintervals
    no wider than ``1 / (4 T)`` (sinc(f T) and cos(2 pi f s) are resolved to ~1e-12)."""
    x, w = _GL8
    nodes, weights = [], []
    for lo, hi in zip(f_hz[:-1], f_hz[1:], strict=True):
        m = int(min(max(1, math.ceil((hi - lo) * window_s * 4.0)), 200_000))
        edges = np.linspace(lo, hi, m + 1)
        half = 0.5 * np.diff(edges)[:, None]
        mid = 0.5 * (edges[:-1] + edges[1:])[:, None]
        nodes.append((mid + half * x).ravel())
        weights.append((half * w).ravel())
    return np.concatenate(nodes), np.concatenate(weights)


def psd_window(
    frequency_hz, psd_px2_per_hz, *, window_s: float, line_time_s: float, n_s: int | None = None
) -> PSDWindow:
    """The motion of one-sided PSD ``psd_px2_per_hz`` (linear between ``frequency_hz``) through a window ``T``.

    Returns the variance about the window mean ``v(s)`` at Gauss-Legendre offsets ``s`` in ``[0, T/2]``, the
    total variance ``int S``, the blur variance ``int S (1 - sinc^2(f T))`` (the mean of ``v``), the rows'
    displacement variance ``int S sinc^2(f T)`` and the row-to-row one ``2 int S sinc^2(f T) (1 - cos 2 pi f dt)``.

    Examples
    --------
    >>> w = psd_window([5e3, 5e4], [3.6e-6, 3.6e-6], window_s=1.126e-3, line_time_s=7.04e-5)
    >>> round(w.variance_px2, 4), w.displacement_variance_px2 < 1e-3
    (0.162, True)
    """
    f = as_float_array("frequency_hz", frequency_hz, ndim=1)
    p = as_float_array("psd_px2_per_hz", psd_px2_per_hz, ndim=1)
    T = check_range("window_s", window_s, 0, None, lo_open=True)
    dt = check_range("line_time_s", line_time_s, 0, None, lo_open=True)
    fn, fw = _frequency_nodes(f, T)
    sw = np.interp(fn, f, p) * fw  # S(f) df at the nodes
    sc = np.sinc(fn * T)
    n = int(n_s) if n_s is not None else int(min(4096, math.ceil(2.0 * f[-1] * T) + 64))
    x, w = np.polynomial.legendre.leggauss(n)
    s = 0.25 * T * (x + 1.0)  # [0, T/2]
    weights = 0.5 * w
    base = float(np.sum(sw * (1.0 + sc * sc)))
    cross = np.empty(n)
    step = max(1, 4_000_000 // fn.size)
    for lo in range(0, n, step):
        cross[lo : lo + step] = np.cos(2.0 * np.pi * np.outer(s[lo : lo + step], fn)) @ (sw * sc)
    v = np.maximum(base - 2.0 * cross, 0.0)
    disp = float(np.sum(sw * sc * sc))
    return PSDWindow(
        s_s=s,
        weights=weights,
        variance_about_mean_px2=v,
        variance_px2=float(np.sum(sw)),
        blur_variance_px2=float(np.sum(sw * (1.0 - sc * sc))),
        displacement_variance_px2=disp,
        line_to_line_variance_px2=float(np.sum(sw * sc * sc * 2.0 * (1.0 - np.cos(2.0 * np.pi * fn * dt)))),
    )


def jitter_psd_otf(nu_cy_per_px, window: PSDWindow) -> np.ndarray:
    """Expected OTF of Gaussian jitter about the window mean: ``(1/T) int exp(-2 pi^2 nu^2 v(s)) ds``.

    Examples
    --------
    >>> w = psd_window([5e3, 5e4], [0.16 / 45e3] * 2, window_s=1.126e-3, line_time_s=7.04e-5)  # sigma 0.4 px
    >>> round(float(jitter_psd_otf(0.5, w)), 4), round(float(np.exp(-2 * np.pi**2 * 0.16 / 4)), 4)
    (0.4541, 0.454)
    """
    nu = as_float_array("nu_cy_per_px", nu_cy_per_px)
    out = np.empty(nu.shape)
    flat, o = nu.ravel(), out.reshape(-1)
    step = max(1, 4_000_000 // window.s_s.size)
    for lo in range(0, flat.size, step):
        q = -2.0 * np.pi**2 * flat[lo : lo + step, None] ** 2
        o[lo : lo + step] = np.exp(q * window.variance_about_mean_px2) @ window.weights
    return out


def drift_otf(nu_x_cy_per_px, nu_y_cy_per_px, *, stages: int, drift_x_px: float, drift_y_px: float) -> np.ndarray:
    """OTF of an image drifting ``(drift_x_px, drift_y_px)`` per TDI stage relative to the charge: a linear smear
    of ``stages`` times that, centred, ``sinc(N (dx nu_x + dy nu_y))`` (real; changes sign past its first zero).

    Examples
    --------
    >>> round(float(drift_otf(0.0, 0.5, stages=16, drift_x_px=0.0, drift_y_px=0.05)), 4)  # sinc(0.4)
    0.7568
    """
    nx, ny = np.broadcast_arrays(np.asarray(nu_x_cy_per_px, float), np.asarray(nu_y_cy_per_px, float))
    return np.sinc(int(stages) * (float(drift_x_px) * nx + float(drift_y_px) * ny))


_LOG_MAX_LINES = 4096  # rows of a line-of-sight log the budget averages over


def log_windows(system, axis: str) -> tuple[np.ndarray, int, int]:
    """``(x, m, K)``: the ``[motion.line_of_sight]`` log's ``axis`` on the time path's grid (``m`` samples per
    line, midpoints, from ``t = 0``) over the rows whose TDI windows it covers (at most 4096), ``K`` samples per
    window. The budget's log terms are taken over these windows."""
    log, dt, n_st = system.motion.line_of_sight, system.line_time_s, system.detector.tdi_stages
    m = samples_per_line(system, dt, n_st)
    span = log.time_s[-1] - log.time_offset_s  # scan time the log reaches
    rows = int(min(_LOG_MAX_LINES, math.floor(span / dt + 1e-9) - n_st))
    if log.time_offset_s < log.time_s[0] - 1e-12 or rows < 1:
        raise ConfigError(
            f"motion.line_of_sight: the log ({log.time_s[0]:.6g} .. {log.time_s[-1]:.6g} s, time_offset_s = "
            f"{log.time_offset_s:g}) does not cover one TDI window ({n_st * dt:.6g} s) from row 0"
        )
    t = (np.arange((rows + n_st) * m) + 0.5) * dt / m
    act, alt = log.at(t)
    return (act if axis == "act" else alt), m, n_st * m


def window_means(x: np.ndarray, m: int, k: int) -> np.ndarray:
    """Each row's window mean of a path ``x`` sampled ``m`` times per line, ``k`` samples per window (rows start
    every ``m`` samples, as many as ``x`` covers): the rows' displacements."""
    c = np.concatenate([[0.0], np.cumsum(x)])
    starts = np.arange((x.size - k) // m + 1) * m
    return (c[starts + k] - c[starts]) / k


def log_otf(nu_cy_per_px, x: np.ndarray, m: int, k: int) -> np.ndarray:
    """Expected OTF (complex) over the rows of a sampled line of sight ``x`` (px; ``m`` samples per line, ``k``
    per window) about each row's window mean: ``mean_i mean_{t in window i} exp(2 pi i nu (x(t) - d_i))``."""
    nu = np.atleast_1d(np.asarray(nu_cy_per_px, dtype=float))
    starts = np.arange((x.size - k) // m + 1) * m
    d = window_means(x, m, k)  # each row's displacement
    out = np.empty(nu.shape, dtype=complex)
    step = max(1, int(2**24 // max(x.size, 1)))
    for a in range(0, nu.size, step):
        f = nu[a : a + step]
        e = np.exp(2j * np.pi * np.outer(x, f))
        ce = np.zeros((x.size + 1, f.size), dtype=complex)
        np.cumsum(e, axis=0, out=ce[1:])
        w = (ce[starts + k] - ce[starts]) / k
        out[a : a + step] = np.mean(w * np.exp(-2j * np.pi * np.outer(d, f)), axis=0)
    return out
