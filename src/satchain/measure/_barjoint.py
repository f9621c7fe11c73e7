"""Joint MTF model of a bar target, to fill harmonics one group cannot observe (see :mod:`satchain.measure.bars`).

All groups of a target are blurred by one system MTF ``M``.  A group of period ``P`` whose harmonic ``k``
folds to 0.5 cy/px and is sampled at its zero crossings (e.g. 6 px with a bar centre half-way between
samples) holds no information on ``A_k``; the other groups' fundamentals sample ``M`` at ``1 / P_j``.  A
smooth non-increasing model ``M(f) = exp(-c1 f - c2 f^2)`` (``c1, c2 >= 0``, ``M(0) = 1``), fitted to the
fundamentals by weighted least squares in ``log M``, predicts ``M(k / P)``; the group is refitted with that
prediction as a prior on the unobserved ``A_k`` only (a pseudo-observation whose 1-sigma is the model's,
statistical and a model-error term), so the prior's uncertainty reaches the CTF 1-sigma.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import nnls

from satchain.measure._barfit import GroupFit

__all__ = ["MtfModel", "fit_mtf_model", "refit_with_prior"]

#: Fewest groups (distinct fundamental frequencies) the joint model needs.
MIN_GROUPS = 3
#: Model error of the log-quadratic form, as a fraction of the predicted log attenuation, growing by 2x per
#: extrapolation ratio beyond the highest fitted frequency.  Checked at 0.5 cy/px from fundamentals up to
#: 0.2-0.4 cy/px: Gaussian (0.4-1 px) x pixel sinc <= 3 %, annular diffraction (q 1-1.5) x pixel <= 19 %.
LOG_MODEL_ERROR = 0.05


def _coltman_gain(k: int) -> float:
    """Square-wave Fourier coefficient of harmonic k (bar centre at the phase): 4 / pi (-1)^((k-1)/2) / k."""
    return 4 / np.pi * (-1.0) ** ((k - 1) // 2) / k


@dataclass(frozen=True)
class MtfModel:
    """``M(f) = exp(-c1 f - c2 f^2)`` with the covariance of ``(c1, c2)`` and the highest frequency fitted."""

    coef: np.ndarray
    cov: np.ndarray
    f_max: float

    def predict(self, f: float) -> tuple[float, float]:
        """``M(f)`` and its 1-sigma (statistical and model error; more where it extrapolates)."""
        x = np.array([f, f * f])
        att = float(x @ self.coef)
        s_stat = float(np.sqrt(max(x @ self.cov @ x, 0.0)))
        s_model = LOG_MODEL_ERROR * att * (1.0 + max(f / self.f_max - 1.0, 0.0) * 2.0)
        m = float(np.exp(-att))
        return m, m * float(np.hypot(s_stat, s_model))


def fit_mtf_model(fits: list[GroupFit], periods, c_large: float) -> MtfModel | None:
    """Fit the model to the groups' fundamentals (P >= 2.5 px, modulation above 3 sigma); None with fewer
    than :data:`MIN_GROUPS` usable groups."""
    fs, logm, sig = [], [], []
    g1 = _coltman_gain(1)
    for fit, p in zip(fits, periods, strict=True):
        if p < 2.5 or fit.cov is None or fit.a <= 0:
            continue
        m = fit.amps[0] / (fit.a * c_large * g1)
        # 1-sigma of A_1 / a from the fit covariance (a, A_1)
        grad = np.array([-fit.amps[0] / fit.a**2, 1 / fit.a])
        s = float(np.sqrt(max(grad @ fit.cov[:2, :2] @ grad, 0.0))) / (c_large * g1)
        if not (m > 3 * s and m > 0):
            continue
        fs.append(1 / p)
        logm.append(-np.log(m))
        sig.append(max(s / m, 1e-4))
    if len(set(np.round(fs, 6))) < MIN_GROUPS:
        return None
    f, y, w = np.array(fs), np.array(logm), 1 / np.array(sig)
    x = np.column_stack([f, f * f])
    coef, _ = nnls(x * w[:, None], y * w)
    resid = (y - x @ coef) * w
    scale = max(1.0, float(np.sum(resid**2)) / max(f.size - 2, 1))  # misfit inflates the covariance
    cov = scale * np.linalg.pinv((x * w[:, None]).T @ (x * w[:, None]))
    return MtfModel(coef, cov, float(f.max()))


def refit_with_prior(profile, period: float, fit: GroupFit, c_large: float, model: MtfModel, noise=None):
    """Refit ``fit`` at its phase with the model's ``M(k / P)`` as a prior on its unobserved harmonics
    (``noise``: the profile's 1-sigma from the rows, if known; the data rows' misfit counts too): returns
    the new fit (modulation and 1-sigma) and ``{k: (M, sigma)}`` used."""
    y = np.asarray(profile, dtype=float)
    x = np.arange(y.size, dtype=float)
    kk = np.asarray(fit.harmonics, dtype=float)
    ph = 2 * np.pi * np.outer(x - fit.x0, kk) / period
    d = np.column_stack([np.ones_like(x), np.cos(ph)])
    prior_rows, used = [], {}
    for k in fit.unobserved:
        m, sm = model.predict(k / period)
        g = c_large * _coltman_gain(k)
        sig = max(abs(fit.a * g) * sm, 1e-9 * fit.a)
        row = np.zeros(d.shape[1])
        row[1 + fit.harmonics.index(k)], row[0] = 1.0, -g * m  # A_k - a C g_k M(k / P) = 0 +- sigma
        prior_rows.append(row / sig)
        used[k] = (m, sm)
    prior = np.array(prior_rows)
    s = noise if noise is not None and np.isfinite(noise) and noise > 0 else 1e-9 * fit.a
    for _ in range(2):  # the second pass with the data rows' misfit if it is larger than the noise
        a_mat = np.vstack([d / s, prior])
        beta = np.linalg.lstsq(a_mat, np.concatenate([y / s, np.zeros(len(prior))]), rcond=None)[0]
        dof = y.size - d.shape[1] - 1 + len(prior)
        s_fit = float(np.sqrt(np.sum((y - d @ beta) ** 2) / max(dof, 1)))
        if s_fit <= s * 1.01:
            break
        s = s_fit
    a, amps = float(beta[0]), beta[1:]
    # covariance with the phase free (its column from the data rows only)
    dx0 = np.sin(ph) @ (amps * 2 * np.pi * kk / period) / s
    jac = np.column_stack([a_mat, np.concatenate([dx0, np.zeros(len(prior))])])
    cov = np.linalg.pinv(jac.T @ jac)
    total = float(np.sum(amps))
    grad = np.zeros(jac.shape[1])
    grad[0] = -abs(total) / a**2
    grad[1 : 1 + kk.size] = np.sign(total) / a
    std = float(np.sqrt(max(grad @ cov @ grad, 0.0)))
    new = replace(fit, a=a, amps=amps, modulation=abs(total) / a, modulation_std=std, noise=s, unobserved=(), cov=cov)
    return new, used
