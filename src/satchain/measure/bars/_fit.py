"""Fit of one bar-group profile at its known period (see :mod:`satchain.measure.bars`).

Model: ``p(x) = a + sum_{k in K} A_k cos(2 pi k (x - x0) / P)`` at the sample positions ``x = 0..L-1``,
``K`` odd harmonics up to 1.5 cy/px whose folded frequencies the samples separate (see
:func:`harmonics_for`), with at most ``L - 3`` of them.  ``x0`` is found by variable projection (grid over
one period, then a bounded scalar minimisation), the rest by linear least squares; the covariance is
``s^2 (J^T J)^-1`` with ``J`` the Jacobian in ``(a, A_k, x0)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

__all__ = ["GroupFit", "fit_group", "harmonics_for", "period_gain", "plateau"]

#: Highest harmonic frequency fitted (cy/px): beyond it a pixel-integrated profile holds little.
F_HARMONIC_MAX = 1.5


@dataclass(frozen=True)
class GroupFit:
    """Fitted mean ``a``, amplitudes ``amps`` (for ``harmonics``), bright-bar-centre phase ``x0`` (px), the
    modulation ``|sum amps| / a`` and its 1-sigma, the profile noise used and the rms misfit."""

    a: float
    harmonics: tuple
    amps: np.ndarray
    x0: float
    modulation: float
    modulation_std: float
    noise: float
    misfit: float
    unobserved: tuple = ()
    cov: np.ndarray | None = None  # covariance of (a, amps..., x0)
    held: tuple = ()  # harmonics set by a prior (the joint MTF model), not by the data

    def peak_trough(self) -> tuple[float, float]:
        """Fitted continuous profile at a bar centre and at a gap centre (bright first)."""
        s = float(np.sum(self.amps))
        return (self.a + abs(s), self.a - abs(s))

    def flatness(self, period: float) -> float:
        """Largest change of the fitted profile within +-P/8 of a bar or gap centre, over its amplitude."""
        u = np.linspace(-period / 8, period / 8, 21)
        out = 0.0
        for c in (0.0, period / 2):
            w = self._wave(c + u, period, 0.0)
            out = max(out, float(np.ptp(w)))
        s = abs(float(np.sum(self.amps)))
        return out / (2 * s) if s > 0 else np.inf

    def _wave(self, x, period, x0):
        k = np.asarray(self.harmonics, dtype=float)
        return self.a + np.cos(2 * np.pi * np.outer(np.asarray(x) - x0, k) / period) @ self.amps


def harmonics_for(period: float, n_samples: int) -> tuple[int, ...]:
    """Odd harmonics identifiable from ``n_samples`` samples of a profile of period ``period`` px.

    Sampling folds harmonic ``k`` to ``g = |k / P - round(k / P)|``; a harmonic is kept when its ``g`` is
    at least ``0.5 / L`` from zero and from every kept one's (two harmonics on one folded frequency could in
    principle be separated by their locked phases, but the fit becomes ill-conditioned: tried and dropped).
    The ones left out alias onto kept ones -- a bias for sharp systems, which a flag reports.
    """
    out: list[int] = []
    folded: list[float] = []
    tol = 0.5 / n_samples
    k = 1
    while k / period <= F_HARMONIC_MAX and len(out) + 4 <= n_samples:
        g = abs(k / period - round(k / period))
        if k == 1 or (g >= tol and all(abs(g - h) >= tol for h in folded)):
            out.append(k)
            folded.append(g)
        k += 2
    return tuple(out)


def _design(x, period, ks, x0):
    return np.column_stack([np.ones_like(x), *(np.cos(2 * np.pi * k * (x - x0) / period) for k in ks)])


def _rss(x, y, period, ks, x0) -> float:
    d = _design(x, period, ks, x0)
    beta, *_ = np.linalg.lstsq(d, y, rcond=None)
    return float(np.sum((y - d @ beta) ** 2))


def fit_group(profile: np.ndarray, period: float, noise: float | None) -> GroupFit:
    """Fit one profile (see the module docstring); ``noise`` is the profile's 1-sigma if known (else the fit
    residual is used)."""
    y = np.asarray(profile, dtype=float)
    x = np.arange(y.size, dtype=float)
    ks = harmonics_for(period, y.size)
    g1 = abs(1 / period - round(1 / period))
    if 0.5 - g1 < 0.02:
        # fundamental at (or within 0.02 cy/px of) 0.5 cy/px: the phase is not identifiable (A cos(pi x0) is);
        # a bar centre on a sample gives the sampled modulation, a lower bound of the CTF
        x0 = float(min(range(int(np.ceil(period))), key=lambda t: _rss(x, y, period, ks, float(t))))
    else:
        grid = np.arange(64) * period / 64
        costs = [_rss(x, y, period, ks, g) for g in grid]
        g0 = grid[int(np.argmin(costs))]
        res = minimize_scalar(
            lambda t: _rss(x, y, period, ks, t),
            bounds=(g0 - period / 64, g0 + period / 64),
            method="bounded",
            options={"xatol": 1e-6 * period},
        )
        x0 = float(res.x)
    x0 = x0 % period
    # a harmonic folded to 0.5 cy/px whose samples all sit near its zero crossings cannot be estimated: it is
    # left out of the fit (amplitude 0, flagged; a multi-group target fills it, see _barjoint)
    norms = np.sqrt(np.mean(_design(x, period, ks, x0)[:, 1:] ** 2, axis=0)) / np.sqrt(0.5)
    unobserved = tuple(int(k) for k, nrm in zip(ks, norms, strict=True) if nrm < 0.3)
    a, amps, cov, s, misfit = _linear_fit(x, y, period, ks, x0, noise, unobserved)
    total = float(np.sum(amps))
    mod = abs(total) / a if a > 0 else np.inf
    std = np.nan
    if cov is not None:
        grad = np.zeros(cov.shape[0])
        grad[0] = -abs(total) / a**2
        grad[1 : 1 + len(ks)] = np.sign(total) / a
        std = float(np.sqrt(max(grad @ cov @ grad, 0.0)))
    if total < 0:  # x0 on a dark bar: move it to a bright one (odd harmonics change sign)
        x0, amps = (x0 + period / 2) % period, -amps
        if cov is not None:  # amplitudes change sign: flip their rows / columns
            sign = np.ones(cov.shape[0])
            sign[1 : 1 + len(ks)] = -1.0
            cov = cov * np.outer(sign, sign)
    return GroupFit(a, ks, amps, x0, float(mod), std, float(s), misfit, unobserved, cov)


def _linear_fit(x, y, period, ks, x0, noise, skip):
    """``a``, amplitudes (0 for the harmonics in ``skip``), covariance of ``(a, A_k, x0)`` (None where
    undefined), the noise used and the rms misfit, at the phase ``x0``."""
    keep = np.array([True] + [k not in skip for k in ks] + [True])
    d = _design(x, period, ks, x0)
    beta = np.zeros(d.shape[1])
    beta[keep[:-1]] = np.linalg.lstsq(d[:, keep[:-1]], y, rcond=None)[0]
    a, amps = float(beta[0]), beta[1:]
    resid = y - d @ beta
    dof = y.size - int(keep.sum())
    s_fit = float(np.sqrt(np.sum(resid**2) / dof)) if dof > 0 else np.nan
    s = noise if noise is not None and np.isfinite(noise) else s_fit
    if noise is not None and np.isfinite(noise) and dof >= 3 and np.isfinite(s_fit):
        s = max(noise, s_fit)  # model error counts too
    misfit = float(np.sqrt(max(s_fit**2 - (noise or 0.0) ** 2, 0.0))) if np.isfinite(s_fit) else 0.0
    kk = np.asarray(ks, dtype=float)
    dx0 = np.sin(2 * np.pi * np.outer(x - x0, kk) / period) @ (amps * 2 * np.pi * kk / period)
    jac = np.column_stack([d, dx0])
    cov = None
    if np.isfinite(s) and a > 0:
        cov = np.zeros((keep.size, keep.size))
        cov[np.ix_(keep, keep)] = s * s * np.linalg.pinv(jac[:, keep].T @ jac[:, keep])
    return a, amps, cov, s, misfit


def period_gain(profile: np.ndarray, period: float) -> tuple[float, float, float]:
    """Least-squares periodogram: the variance explained by one sinusoid (free phase, with a mean) at the
    claimed frequency ``1 / period`` (folded), the largest one elsewhere (beyond 0.6 / L from it, on a
    quarter-bin grid of [0.5 / L, 0.5]), and the frequency of that largest one (cy/px)."""
    y = np.asarray(profile, dtype=float)
    x = np.arange(y.size, dtype=float)
    g_claim = abs(1 / period - round(1 / period))

    def gain(f):
        d = np.column_stack([np.ones_like(x), np.cos(2 * np.pi * f * x), np.sin(2 * np.pi * f * x)])
        beta, *_ = np.linalg.lstsq(d, y, rcond=None)
        return float(np.sum((d @ beta - beta[0]) ** 2))

    freqs = np.arange(0.5 / y.size, 0.5 + 1e-9, 0.25 / y.size)
    others = [(gain(f), f) for f in freqs if abs(f - g_claim) > 0.6 / y.size]
    best = max(others) if others else (0.0, float("nan"))
    return gain(g_claim), best[0], float(best[1])


def plateau(prof: np.ndarray, fit: GroupFit, period: float, force: bool = False, noise: float | None = None):
    """Modulation and 1-sigma from the samples within P/8 of the bar and gap centres, when those are flat
    (a plateau: bars wide enough for the blur; the samples then are the peak and trough themselves), else
    None; and the relative spread found.  Needs P >= 8 px and samples within +-P/8 of each centre at
    distinct distances from it (flatness is seen within one bar, not across bars or mirror samples).

    The spread is the top's drop at P/8 from its centre (the samples' parabola, whatever the grid phase) less
    3 sigma of ``noise``, the profile's measurement noise (from the rows; the fit's residual, which holds the
    periodic model's misfit, only when not given: that misfit hid a curved top at most phases, issue 18).  A
    long-tailed PSF (diffraction: the line spread falls as 1 / x^2) curves the top and holds it below the
    large-area level by about 5.5 times that drop in contrast (obscured pupil, Q = 1, 16 px: drop 1.5 %,
    contrast 8.5 % low); the threshold (0.5 %) keeps the large-area contrast within ~3 %."""
    if period < 8.0:
        return None, np.inf
    x = np.arange(prof.size, dtype=float)
    u = (x - fit.x0) % period
    d_bright, d_dark = np.minimum(u, period - u), np.abs(u - period / 2)
    near_b, near_d = d_bright <= period / 8, d_dark <= period / 8
    bright, dark = prof[near_b], prof[near_d]
    if bright.size < 2 or dark.size < 2:
        return None, np.inf
    b, d = float(np.mean(bright)), float(np.mean(dark))
    if not b > d:
        return None, np.inf
    # the profile is symmetric about a centre, ~ peak - kappa dist^2: the samples' spread shows the drop
    # from the peak only through their distinct distances (two samples at +-0.5 px are equal on any peak:
    # 8 px at sigma 0.8 px read 0.919 for 0.963), scaled to the drop at the farthest one; when all sit at one
    # distance (e.g. +-0.5 px at 8 px) the check reaches out to 3P/16 (still on the bar top for a flat one)
    wide = min(period / 8 + 1.0, 3 * period / 16)
    s = noise if noise is not None and np.isfinite(noise) else fit.noise
    drop = max(_drop(prof, dist, period / 8, wide, s) for dist in (d_bright, d_dark))
    spread = drop / (b - d)
    if spread > 0.005 and not force:
        return None, spread
    sd = float(fit.noise * np.sqrt(1 / bright.size + 1 / dark.size) * 2 * np.sqrt(b * b + d * d) / (b + d) ** 2)
    return ((b - d) / (b + d), sd), spread


def _drop(prof: np.ndarray, dist: np.ndarray, near: float, wide: float, noise: float) -> float:
    """Spread of the samples within ``near`` of a centre (within ``wide`` if they all sit at one distance)
    less 3 noise sigma, scaled by ``near^2 / (dmax^2 - dmin^2)``: a parabolic top's drop from the centre to
    ``near``, the same at every grid phase; inf when all sit at one distance (nothing seen)."""
    for lim in (near, wide):
        sel = dist <= lim
        d2 = dist[sel] ** 2
        span = float(d2.max() - d2.min()) if d2.size else 0.0
        if span >= 0.05:
            return max(float(np.ptp(prof[sel])) - 3 * noise, 0.0) * near * near / span
    return np.inf
