"""An edge's motion transfer over its region's rows (issue 29, item 11), for :class:`PushbroomTerms`
(:mod:`satchain.tf.pushbroom`).

The budget's motion terms (:meth:`PushbroomTerms.components`) are the expected OTF about each row's window mean:
what an edge measures with each line located (:func:`per_row_otf`, on one axis).  An edge measured as imaged (ISO
12233: one straight edge through its lines, the lines' displacements folded into the ESF) sees the motion's whole
path over its region's rows about that straight line: :func:`as_imaged_otf`; :func:`displacement_factor` is the
part of given rows' displacements alone.
"""

from __future__ import annotations

import math

import numpy as np

from satchain.errors import ConfigError
from satchain.tf.pushbroom_otf import _frequency_nodes, jitter_psd_otf, log_otf, oscillation_otf

__all__ = ["as_imaged_otf", "displacement_factor", "per_row_otf", "rows_blur_otf"]


def displacement_factor(nu_cy_per_px, d_px, *, about_line: bool = True) -> np.ndarray:
    """What the rows' displacements ``d_px`` do to an edge measured as imaged (ISO 12233: one straight edge
    through the rows, their displacements folded into the ESF): ``|mean_i exp(2 pi i nu r_i)|``, the
    characteristic function of the displacements ``r_i`` about the least-squares straight line through them (the
    edge's fitted tilt absorbs a linear trend), or about their mean (``about_line`` False).  The MTF as imaged
    is the per-row MTF (the budget's motion terms) times this factor.

    Examples
    --------
    >>> d = 0.5 * np.sin(2 * np.pi * np.arange(400) / 40.0)  # whole periods, about the mean: J0(2 pi nu A)
    >>> from scipy.special import j0
    >>> round(float(displacement_factor(0.5, d, about_line=False)[0]), 4), round(float(j0(np.pi * 0.5)), 4)
    (0.472, 0.472)
    """
    nu = np.atleast_1d(np.asarray(nu_cy_per_px, dtype=float))
    d = np.asarray(d_px, dtype=float).ravel()
    i = np.arange(d.size, dtype=float)
    r = d - (np.polyval(np.polyfit(i, d, 1), i) if about_line and d.size > 2 else d.mean())
    return np.abs(np.mean(np.exp(2j * np.pi * np.outer(nu, r)), axis=1))


def _line_detrended_fraction(f_hz: np.ndarray, line_time_s: float, n_lines: int, degree: int = 1) -> np.ndarray:
    """The expected fraction of a sinusoid's variance at ``f_hz`` sampled on ``n_lines`` lines that is left
    about the least-squares polynomial of ``degree`` (1: the straight line) through them: ``1 - |P e|^2 / n``
    (``P`` the projection on ``(1, i, .., i^degree)``, ``e_i = exp(2 pi i f i dt)``)."""
    i = np.arange(n_lines, dtype=float)
    t = (i - i.mean()) / max(float(np.ptp(i)), 1.0)
    q = np.linalg.qr(np.vander(t, min(int(degree), n_lines - 1) + 1))[0]  # orthonormal basis of the polynomials
    out = np.empty(f_hz.size)
    step = max(1, 2_000_000 // max(n_lines, 1))
    for lo in range(0, f_hz.size, step):
        e = np.exp(2j * np.pi * np.outer(f_hz[lo : lo + step] * line_time_s, i))
        out[lo : lo + step] = 1.0 - np.sum(np.abs(e @ q) ** 2, axis=1) / n_lines
    return out


def per_row_otf(terms, nu_cy_per_px, axis: str) -> np.ndarray:
    """The budget's motion terms on ``axis`` (cy/px of it): the expected OTF about each row's window mean, the
    product of its oscillations', jitter PSD's, line-of-sight log's and TDI drift's (complex)."""
    nu = np.atleast_1d(np.asarray(nu_cy_per_px, dtype=float))
    out = np.ones(nu.shape, dtype=complex)
    for osc in terms.system.motion.oscillation:
        if osc.axis == axis:
            out *= oscillation_otf(
                nu, amplitude_px=osc.amplitude_px, cycles_per_window=osc.frequency_hz * terms.window_s
            )
    if axis in terms.psd:
        out *= jitter_psd_otf(nu, terms.psd[axis])
    if axis in terms.log and np.ptp(terms.log[axis][0]) > 0:
        out *= log_otf(nu, *terms.log[axis])
    drift = 0.0 if terms.drift_px is None else terms.drift_px[0 if axis == "act" else 1]
    return out * np.sinc(terms.stages * drift * nu)


def as_imaged_otf(
    terms, nu_cy_per_px, axis: str, *, first_line: int, n_lines: int, about_line: bool = True, degree: int = 1
):
    """The motion's OTF on ``axis`` (cy/px of it) for an edge measured as imaged over the image rows
    ``first_line .. first_line + n_lines - 1`` (ISO 12233: one straight edge through the rows, their
    displacements folded into the ESF): ``|mean_i mean_(t in window i) exp(2 pi i nu (x(t) - L_i))|`` with
    ``L`` the least-squares line through the rows' window means (their mean: ``about_line`` False; a
    polynomial of ``degree`` > 1: an edge located as a curve of that degree, its lines' departures folded), exactly
    for the oscillations, the line-of-sight log and the TDI drift (their path on the rows' windows), times
    the jitter PSD's Gaussian expectation: its per-row term and ``exp(-2 pi^2 nu^2 v)``, ``v = int S
    sinc^2(f T) g(f) df`` the rows' displacement variance left about that line (:func:`_line_detrended_fraction`,
    ``g = 1`` about the mean).  The per-row counterpart is :func:`per_row_otf`.

    Examples
    --------
    >>> from satchain import load_preset
    >>> osc = {"axis": "act", "amplitude_px": 1.0, "frequency_hz": 100.0}  # slow: it displaces the rows
    >>> from satchain.tf.pushbroom import PushbroomTerms
    >>> t = PushbroomTerms(load_preset("ankarasat3").replace({"motion.oscillation": [osc]}))
    >>> bool(as_imaged_otf(t, 0.5, "act", first_line=0, n_lines=400)[0] < abs(per_row_otf(t, 0.5, "act")[0]))
    True
    """
    nu = np.atleast_1d(np.asarray(nu_cy_per_px, dtype=float))
    n, dt, t_w = int(n_lines), terms.line_time_s, terms.window_s
    if n < 1 or int(first_line) < 0:
        raise ConfigError(f"n_lines = {n_lines}, first_line = {first_line}: need n_lines >= 1 and first_line >= 0")
    x = _window_paths(terms, axis, int(first_line), n)
    d = x.mean(axis=1)
    i = np.arange(n, dtype=float)
    deg = max(1, min(int(degree), n - 2))
    ref = np.polyval(np.polyfit(i - i.mean(), d, deg), i - i.mean()) if about_line and n > 2 else np.full(n, d.mean())
    r = (x - ref[:, None]).ravel()
    out = np.empty(nu.shape)
    step = max(1, 4_000_000 // max(r.size, 1))
    for lo in range(0, nu.size, step):
        out[lo : lo + step] = np.abs(np.mean(np.exp(2j * np.pi * np.outer(nu[lo : lo + step], r)), axis=1))
    for table in terms.system.motion.jitter_psd:
        if table.axis == axis:
            f = np.asarray(table.frequency_hz, float)
            fn, fw = _frequency_nodes(f, t_w)
            left = _line_detrended_fraction(fn, dt, n, deg) if about_line and n > 2 else np.ones(fn.size)
            v = float(np.sum(np.interp(fn, f, table.psd_px2_per_hz) * fw * np.sinc(fn * t_w) ** 2 * left))
            out = out * np.exp(-2.0 * np.pi**2 * nu**2 * v)
    if axis in terms.psd:
        out = out * jitter_psd_otf(nu, terms.psd[axis])
    return out


def rows_blur_otf(terms, nu_cy_per_px, axis: str, *, first_line: int, n_lines: int) -> np.ndarray:
    """The motion's blur on ``axis`` (cy/px of it) about each row's own window mean, averaged over the image rows
    ``first_line .. first_line + n_lines - 1`` as their paths are (not the budget's expectation over the
    oscillations' phases, :func:`per_row_otf`): ``|mean_i mean_(t in window i) exp(2 pi i nu (x(t) - d_i))|``,
    exactly for the oscillations, the log and the TDI drift together (an oscillation whose velocity opposes a
    drift on these rows shortens its smear), times the jitter PSD's per-row expectation. What a target a few
    rows tall sees; the rows' displacements ``d_i`` themselves are left to the image geometry."""
    nu = np.atleast_1d(np.asarray(nu_cy_per_px, dtype=float))
    if int(n_lines) < 1 or int(first_line) < 0:
        raise ConfigError(f"n_lines = {n_lines}, first_line = {first_line}: need n_lines >= 1 and first_line >= 0")
    x = _window_paths(terms, axis, int(first_line), int(n_lines))
    r = (x - x.mean(axis=1, keepdims=True)).ravel()
    out = np.empty(nu.shape)
    step = max(1, 4_000_000 // max(r.size, 1))
    for lo in range(0, nu.size, step):
        out[lo : lo + step] = np.abs(np.mean(np.exp(2j * np.pi * np.outer(nu[lo : lo + step], r)), axis=1))
    return out * np.abs(jitter_psd_otf(nu, terms.psd[axis])) if axis in terms.psd else out


def _window_paths(terms, axis: str, first: int, n: int) -> np.ndarray:
    """(rows, samples) the deterministic motion on ``axis`` over each row's TDI window (oscillations, the
    log, the TDI drift), sampled at the log's grid or at window midpoints (>= 24 a period, >= 32 a window)."""
    dt, t_w = terms.line_time_s, terms.window_s
    if axis in terms.log:
        xl, m, k = terms.log[axis]
        if (first + n - 1) * m + k > xl.size:
            raise ConfigError(
                f"motion.line_of_sight: rows {first} .. {first + n - 1} reach past the rows its log covers "
                f"({(xl.size - k) // m + 1})"
            )
        x = xl[(first + np.arange(n))[:, None] * m + np.arange(k)[None, :]]
        s = (np.arange(k) + 0.5) * dt / m
    else:
        f_top = max((o.frequency_hz for o in terms.system.motion.oscillation if o.axis == axis), default=0.0)
        k = int(min(4096, max(32, math.ceil(24.0 * f_top * t_w))))
        s = (np.arange(k) + 0.5) * t_w / k
        x = np.zeros((n, k))
    t = (first + np.arange(n))[:, None] * dt + s[None, :]
    for osc in terms.system.motion.oscillation:
        if osc.axis == axis:
            x = x + osc.amplitude_px * np.sin(2 * np.pi * osc.frequency_hz * t + math.radians(osc.phase_deg))
    drift = 0.0 if terms.drift_px is None else terms.drift_px[0 if axis == "act" else 1]
    return x + drift * s[None, :] / dt
