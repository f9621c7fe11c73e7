"""Joint MTF model of a bar target, for the harmonics one group cannot observe (see :mod:`satchain.measure.bars`).

One group's samples cannot tell every harmonic apart.  At 4 px harmonic 3 (0.75 cy/px) folds exactly onto
the fundamental; with the phase free, ``(A_1, A_3, x0)`` then explain the same samples along a whole curve,
and the peak-to-trough ``sum A_k`` moves along it (up to ``2 |A_3|``: 0.044 of CTF at 4 px for a Gaussian
PSF of 0.4 px).  At 6 px harmonic 3 folds to 0.5 cy/px and is sampled at its zero crossings at some phases;
at 3 px it folds onto the mean.  No method can recover these from the group alone: its samples are exactly
those of another MTF (the flag says so).

All groups of a target are blurred by one system MTF ``M``, which their fundamentals sample at ``1 / P``.  The
model ``M(f) = sinc(f) exp(-c1 f - c2 f^2)`` (a 100 %-fill square pixel times a smooth non-increasing optics /
motion term, ``c1, c2 >= 0``, ``M(0) = 1``; signed, so it is negative between 1 and 2 cy/px like the pixel's
OTF) is fitted to the fundamentals by weighted least squares in ``log(M / sinc)``.  Each group is then refitted
with the phase free, all its odd harmonics up to 1.5 cy/px in the model, and ``M(k / P)`` as a prior on every
harmonic it cannot observe (a pseudo-observation whose 1-sigma is the model's: statistical plus a model-error
term growing with the extrapolation), so the prior's uncertainty reaches the CTF 1-sigma.  The fundamentals
are then free of the aliased harmonics, the model is refitted, and so on to a fixed point (a contraction:
the aliased terms are a few % of the fundamentals).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar, nnls

from satchain.measure.bars._fit import F_HARMONIC_MAX, GroupFit, _design

__all__ = ["MtfModel", "fit_mtf_model", "held_harmonics", "prior_harmonics", "refit_with_prior"]

#: Fewest groups (distinct fundamental frequencies) the joint model needs.
MIN_GROUPS = 3
#: Model error of ``c1 f + c2 f^2`` as a fraction of the predicted attenuation (the log of the optics term),
#: growing by 2x per extrapolation ratio beyond the highest fitted frequency.  Checked from fundamentals up to
#: 0.2-0.4 cy/px: exact for a Gaussian PSF; annular diffraction (Q 1-1.5, 33 % obscuration) within 5 % at
#: 0.5 cy/px and within the grown band at 0.75-1.25 cy/px (tests/measure/test_bars_joint.py).
LOG_MODEL_ERROR = 0.05
#: Harmonics above this frequency (cy/px) are held at the model in the joint refit, not fitted.
HOLD_ABOVE = 1.0
#: ... and those folding below this many cycles per region length.
HOLD_FOLDED = 1.0
#: Relative floor of the data 1-sigma in the joint refit (noise-free profiles: keeps it well conditioned).
NOISE_FLOOR = 1e-6


def _coltman_gain(k: int) -> float:
    """Square-wave Fourier coefficient of harmonic k (bar centre at the phase): 4 / pi (-1)^((k-1)/2) / k."""
    return 4 / np.pi * (-1.0) ** ((k - 1) // 2) / k


@dataclass(frozen=True)
class MtfModel:
    """``M(f) = sinc(f) exp(-c1 f - c2 f^2 - r(f))``: the smooth form's coefficients and their covariance,
    and ``r``, its residuals at the measured frequencies ``nodes_f`` (``r(0) = 0``), interpolated linearly in
    between and held at the last one beyond ``f_max`` (the form alone misses the shoulder of an obscured
    pupil's MTF by up to 10 %; the measured points do not)."""

    coef: np.ndarray
    cov: np.ndarray
    f_max: float
    nodes_f: np.ndarray = field(default_factory=lambda: np.zeros(1))
    nodes_r: np.ndarray = field(default_factory=lambda: np.zeros(1))

    def predict(self, f: float) -> tuple[float, float]:
        """``M(f)`` (signed) and its 1-sigma (statistical and model error; more where it extrapolates)."""
        m = float(self.mtf(np.array([f]))[0])
        return m, abs(m) * float(self.log_sigma(np.array([f]))[0])

    def attenuation(self, f) -> np.ndarray:
        """``-log(M(f) / sinc(f))``."""
        f = np.abs(np.asarray(f, dtype=float))
        return self.coef[0] * f + self.coef[1] * f * f + np.interp(f, self.nodes_f, self.nodes_r)

    def mtf(self, f, shift: float = 0.0) -> np.ndarray:
        """``M(f)`` at an array of frequencies, its attenuation moved by ``shift`` 1-sigma (``shift = +1``: a
        sharper system by the model's own uncertainty)."""
        f = np.abs(np.asarray(f, dtype=float))
        att = self.attenuation(f)
        # the shift is capped at half the attenuation: a sharper model still decays (no overflow far out)
        return np.sinc(f) * np.exp(-att + shift * np.minimum(self.log_sigma(f), 0.5 * np.abs(att)))

    def log_sigma(self, f) -> np.ndarray:
        """1-sigma of ``log M(f)``: the coefficients' covariance, the model error (a fraction of the
        attenuation) and the interpolation's (half the residuals' step across the interval; beyond the last
        measured frequency half the last residual), the last two growing where it extrapolates."""
        f = np.abs(np.asarray(f, dtype=float))
        x = np.stack([f, f * f], axis=-1)
        s_stat = np.sqrt(np.maximum(np.einsum("...i,ij,...j->...", x, self.cov, x), 0.0))
        grow = 1.0 + np.maximum(f / self.f_max - 1.0, 0.0) * 2.0
        s_model = LOG_MODEL_ERROR * np.abs(self.attenuation(f)) * grow
        nf, nr = self.nodes_f, self.nodes_r
        j = np.clip(np.searchsorted(nf, f) - 1, 0, max(nf.size - 2, 0))
        step = np.abs(nr[np.minimum(j + 1, nf.size - 1)] - nr[j])
        s_interp = np.where(f > nf[-1], 0.5 * np.abs(nr[-1]) * grow, 0.5 * step)
        return np.sqrt(s_stat**2 + s_model**2 + s_interp**2)

    def ctf(self, period: float, shift: float = 0.0) -> float:
        """Coltman's square-wave CTF of the model at ``1 / period``: 4 / pi sum_k odd (-1)^((k-1)/2) M(k / P) / k."""
        k = np.arange(1, 2001, 2)
        return float(4 / np.pi * np.sum((-1.0) ** ((k - 1) // 2) * self.mtf(k / period, shift) / k))

    def render_group(self, period: float, centres, length: int, contrast: float, shift: float = 0.0) -> np.ndarray:
        """Profile of bright bars (width ``P / 2``, centres ``centres`` px) on a plate, levels ``1 -+ contrast``,
        through the model at ``shift`` (pixel aperture included), at the samples ``x = 0 .. length - 1``:
        ``1 - C + 2 C sum_j [E(x - c_j + P/4) - E(x - c_j - P/4)]`` with the edge response
        ``E(d) = 1/2 + int_0^inf M(f) sin(2 pi f d) / (pi f) df`` (Gauss-Legendre, one oscillation per panel)."""
        x = np.arange(length, dtype=float)
        c = np.asarray(centres, dtype=float)
        d = np.concatenate([x[:, None] - c[None, :] + period / 4, x[:, None] - c[None, :] - period / 4], axis=1)
        big = float(np.max(np.abs(d))) + 1.0
        f_top = _decay_limit(self.coef)
        n_panels = max(int(np.ceil(f_top * big)), 8)
        g, w = np.polynomial.legendre.leggauss(16)
        edges = np.linspace(0.0, f_top, n_panels + 1)
        half = 0.5 * np.diff(edges)
        f = (edges[:-1, None] + half[:, None] * (g[None, :] + 1)).ravel()
        wt = (half[:, None] * w[None, :]).ravel() * self.mtf(f, shift) / (np.pi * f)
        e = 0.5 + np.sin(2 * np.pi * d[..., None] * f) @ wt
        n = c.size
        return 1.0 - contrast + 2.0 * contrast * np.sum(e[:, :n] - e[:, n:], axis=1)


def _decay_limit(coef) -> float:
    """Frequency (cy/px) beyond which the optics term ``exp(-c1 f - c2 f^2)`` is below 1e-7 (at most 40)."""
    c1, c2 = float(coef[0]), float(coef[1])
    target = np.log(1e7)
    if c2 > 0:
        f = (-c1 + np.sqrt(c1 * c1 + 4 * c2 * target)) / (2 * c2)
    elif c1 > 0:
        f = target / c1
    else:
        f = 40.0
    return float(min(max(f, 2.0), 40.0))


def fit_mtf_model(fits: list[GroupFit], periods, c_large: float) -> MtfModel | None:
    """Fit the model to the groups' fundamentals (P >= 2.5 px) and the harmonics they observe below 1 cy/px
    (not those held by a prior), each with its 1-sigma, where above 3 sigma; None with fewer than
    :data:`MIN_GROUPS` groups giving a fundamental."""
    fs, logm, sig, fund = [], [], [], set()
    for fit, p in zip(fits, periods, strict=True):
        if p < 2.5 or fit.cov is None or fit.a <= 0:
            continue
        held = set(fit.held)
        for j, k in enumerate(fit.harmonics):
            f = k / p
            if k in held or k in fit.unobserved or f >= 1.0:
                continue
            g = c_large * _coltman_gain(k)
            m = fit.amps[j] / (fit.a * g)
            # 1-sigma of A_k / a from the fit covariance (a, ..., A_k, ...)
            idx = [0, 1 + j]
            grad = np.array([-fit.amps[j] / fit.a**2, 1 / fit.a])
            s = float(np.sqrt(max(grad @ fit.cov[np.ix_(idx, idx)] @ grad, 0.0))) / abs(g)
            if not (m > 3 * s and m > 0):
                continue
            fs.append(f)
            logm.append(-np.log(m / np.sinc(f)))
            sig.append(max(s / m, 1e-4))
            if k == 1:
                fund.add(round(f, 6))
    if len(fund) < MIN_GROUPS:
        return None
    f, y, w = np.array(fs), np.array(logm), 1 / np.array(sig)
    x = np.column_stack([f, f * f])
    coef, _ = nnls(x * w[:, None], y * w)
    resid = (y - x @ coef) * w
    scale = max(1.0, float(np.sum(resid**2)) / max(f.size - 2, 1))  # misfit inflates the covariance
    cov = scale * np.linalg.pinv((x * w[:, None]).T @ (x * w[:, None]))
    # residuals of the smooth form, one per measured frequency (weighted mean of coincident ones), r(0) = 0
    r = y - x @ coef
    keys = np.round(f, 6)
    nf = np.unique(keys)
    nr = np.array([np.average(r[keys == k], weights=w[keys == k] ** 2) for k in nf])
    return MtfModel(coef, cov, float(f.max()), np.concatenate([[0.0], nf]), np.concatenate([[0.0], nr]))


def prior_harmonics(fit: GroupFit, period: float) -> tuple[int, ...]:
    """Odd harmonics up to 1.5 cy/px the group's own fit could not observe: aliased onto a fitted one (left
    out of it) or sampled at their zero crossings."""
    out = [k for k in range(3, int(F_HARMONIC_MAX * period) + 1, 2) if k not in fit.harmonics]
    return tuple(sorted({*out, *fit.unobserved}))


def held_harmonics(ks, period: float, n_samples: int) -> tuple[int, ...]:
    """Harmonics (k > 1) the joint refit holds at the model rather than fits: above :data:`HOLD_ABOVE` cy/px
    (small behind the pixel aperture), or folding below ``HOLD_FOLDED / L`` cy/px, where over the region they
    look like the finite group's smooth hump (3.3 px: harmonic 3 folds to 0.09 cy/px)."""
    out = []
    for k in ks:
        g = abs(k / period - round(k / period))
        if k > 1 and (k / period > HOLD_ABOVE or g < HOLD_FOLDED / n_samples):
            out.append(int(k))
    return tuple(out)


def _solve(x, y, period, ks, x0, s, prior):
    """Weighted least squares of the data rows (1-sigma ``s``) and the prior rows at phase ``x0``: the
    coefficients ``(a, A_k...)`` and the cost."""
    d = _design(x, period, ks, x0) / s
    mat = np.vstack([d, prior])
    rhs = np.concatenate([y / s, np.zeros(prior.shape[0])])
    beta = np.linalg.lstsq(mat, rhs, rcond=None)[0]
    return beta, float(np.sum((mat @ beta - rhs) ** 2))


def _grid_costs(x, y, period, ks, grid, s, prior) -> np.ndarray:
    """:func:`_solve`'s cost at every phase of ``grid`` in one batch: the same least squares (NumPy's
    ``lstsq``: SVD, singular values below ``eps max(shape)`` of the largest dropped), stacked; the cost is the
    residual of projecting the right-hand side on the kept singular vectors."""
    kk = np.asarray(ks, dtype=float)
    ph = 2 * np.pi * (x[None, :, None] - np.asarray(grid, dtype=float)[:, None, None]) * kk / period
    data = np.concatenate([np.ones((len(grid), x.size, 1)), np.cos(ph)], axis=2) / s
    mat = np.concatenate([data, np.broadcast_to(prior, (len(grid), *prior.shape))], axis=1)
    rhs = np.concatenate([y / s, np.zeros(prior.shape[0])])
    u, sv, _ = np.linalg.svd(mat, full_matrices=False)
    keep = sv > np.finfo(float).eps * max(mat.shape[1:]) * sv[:, :1]
    proj = np.where(keep, np.einsum("gnm,n->gm", u, rhs), 0.0)
    return np.sum((rhs - np.einsum("gnm,gm->gn", u, proj)) ** 2, axis=1)


def refit_with_prior(profile, period: float, fit: GroupFit, model: MtfModel, noise=None):
    """Refit ``fit`` with the phase free, every odd harmonic up to 1.5 cy/px in the model, and the model's
    ``M(k / P)`` as a prior on the harmonics the group cannot observe (``noise``: the profile's 1-sigma from
    the rows, if known; the data rows' misfit counts too): returns the new fit and ``{k: (M, sigma)}`` used."""
    y = np.asarray(profile, dtype=float)
    x = np.arange(y.size, dtype=float)
    # harmonics above 1 cy/px are small (pixel aperture) and, when fitted freely, soak up the finite group's
    # hump (e.g. 2.5 px: harmonic 3 folds to 0.2 cy/px): they are held at the model, not fitted
    ks0 = tuple(sorted({*fit.harmonics, *prior_harmonics(fit, period)}))
    hold = held_harmonics(ks0, period, y.size)
    pk = tuple(sorted({*prior_harmonics(fit, period), *hold}))
    ks = ks0
    # the prior ties A_k to the group's own fundamental, A_k = A_1 g_k M(k / P) / (g_1 M(1 / P)): sign-free
    # under a half-period shift of x0 (a dark bar centre flips every odd harmonic) and free of the levels
    m1, _ = model.predict(1 / period)
    a1 = abs(float(fit.amps[0]))
    s = noise if noise is not None and np.isfinite(noise) and noise > 0 else 0.0
    s = max(s, NOISE_FLOOR * abs(fit.a))
    prior_rows, used, held_sig = [], {}, {}
    for k in pk:
        m, sm = model.predict(k / period)
        rho = _coltman_gain(k) * m / (_coltman_gain(1) * m1)
        sig = max(abs(rho) * a1 * sm / max(abs(m), 1e-300), 1e-9 * abs(fit.a))
        if k in hold:  # held: a row far stronger than the data; its uncertainty is propagated below
            held_sig[k] = sig / max(a1, 1e-300)
            sig = 1e-3 * s
        row = np.zeros(1 + len(ks))
        row[1 + ks.index(k)], row[1] = 1.0, -rho  # A_k - rho_k A_1 = 0 +- sigma
        prior_rows.append(row / sig)
        used[k] = (m, sm)
    prior = np.array(prior_rows).reshape(len(prior_rows), 1 + len(ks))
    for _ in range(3):  # again with the data rows' misfit if it is larger than the noise
        x0 = _best_phase(x, y, period, ks, s, prior)
        beta, _ = _solve(x, y, period, ks, x0, s, prior)
        dof = y.size - len(ks) - 2 + len(pk)
        s_fit = float(np.sqrt(np.sum((y - _design(x, period, ks, x0) @ beta) ** 2) / max(dof, 1)))
        if s_fit <= s * 1.01:
            break
        s = s_fit
    a, amps = float(beta[0]), beta[1:]
    kk = np.asarray(ks, dtype=float)
    ph = 2 * np.pi * np.outer(x - x0, kk) / period
    # covariance with the phase free (its column from the data rows only)
    dx0 = np.sin(ph) @ (amps * 2 * np.pi * kk / period) / s
    jac = np.column_stack(
        [np.vstack([_design(x, period, ks, x0) / s, prior]), np.concatenate([dx0, np.zeros(len(pk))])]
    )
    cov = np.linalg.pinv(jac.T @ jac)
    total = float(np.sum(amps))
    if total < 0:  # x0 on a dark bar: move it to a bright one (odd harmonics change sign)
        x0, amps, total = x0 + period / 2, -amps, -total
        sign = np.ones(cov.shape[0])
        sign[1 : 1 + kk.size] = -1.0
        cov = cov * np.outer(sign, sign)
    grad = np.zeros(jac.shape[1])
    grad[0] = -total / a**2
    grad[1 : 1 + kk.size] = 1 / a
    var = max(float(grad @ cov @ grad), 0.0)
    for k, sr in held_sig.items():  # a held harmonic moved by its 1-sigma: the modulation's change
        moved = prior.copy()
        j = pk.index(k)
        moved[j, 1] -= sr * moved[j, 1 + ks.index(k)]
        b2, _ = _solve(x, y, period, ks, x0, s, moved)
        var += (abs(float(np.sum(b2[1:]))) / b2[0] - total / a) ** 2
    std = float(np.sqrt(var))
    misfit = float(np.sqrt(max(s_fit**2 - (noise or 0.0) ** 2, 0.0)))
    new = GroupFit(a, ks, amps, float(x0 % period), total / a, std, s, misfit, (), cov, pk)
    return new, used


def _best_phase(x, y, period, ks, s, prior):
    """Phase minimising the joint cost: a grid over one period, then a bounded scalar minimisation."""
    grid = np.arange(64) * period / 64
    g0 = grid[int(np.argmin(_grid_costs(x, y, period, ks, grid, s, prior)))]
    res = minimize_scalar(
        lambda t: _solve(x, y, period, ks, t, s, prior)[1],
        bounds=(g0 - period / 64, g0 + period / 64),
        method="bounded",
        options={"xatol": 1e-7 * period},
    )
    return float(res.x)
