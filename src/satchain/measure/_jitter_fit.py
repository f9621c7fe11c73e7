"""Sinusoids in line-by-line edge positions (used by :mod:`satchain.measure.jitter`); pure arrays.

Model of the positions ``x_j`` at times ``t_j = line_j * line_time`` (missing lines simply absent):

    x_j = c0 + c1 line_j                                   (the edge's own tilt)
          + sum_h [p_h cos(2 pi h x_j) + q_h sin(2 pi h x_j)]   (a bias locked to the sub-pixel phase, h = 1..3)
          + sum_k A_k sin(2 pi f_k t_j + phi_k) + noise.

The phase-locked terms are nuisance parameters: with an edge profile estimated from the same lines, a motion
locked to the edge's sub-pixel phase cannot be told from a change of that profile (the lines' positions and the
profile trade any function of the phase), so the estimator may leave a small error of that form, and such a
motion is not measurable.

Peaks are found one at a time (prewhitening): the generalised Lomb-Scargle periodogram of the positions with
the model so far as the null (``z(f)`` = the fraction of the residual sum of squares a sinusoid at ``f``
explains, on a grid from half a cycle per record to the line-rate Nyquist ``1 / (2 line_time)``), its highest
peak tested against the noise with Baluev's (2008) false-alarm probability for the maximum over the band
(MNRAS 385, 1279; as astropy's ``false_alarm_probability(method="baluev")``), and, when significant, every
sinusoid and nuisance term refitted jointly by nonlinear least squares (frequencies free).  Parameter
uncertainties are ``s^2 (J^T J)^-1`` at the solution with ``s^2`` the residual variance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, least_squares
from scipy.special import gammaln

__all__ = ["SineFit", "baluev_fap", "fit_sinusoids", "periodogram", "threshold_z"]

N_PHASE_HARMONICS = 3
_OVERSAMPLE = 8  # frequency grid points per 1 / record length
_CHUNK = 2_000_000  # samples x frequencies per block of the periodogram


@dataclass(frozen=True)
class SineFit:
    """Joint fit: ``freq_hz, amp_px, phase_rad`` (phase at ``t = 0``) and their 1-sigma, the model at the
    lines, the nuisance part (trend + phase-locked terms), the residuals, the number of parameters and the
    nuisance coefficients."""

    freq_hz: np.ndarray
    freq_sigma_hz: np.ndarray
    amp_px: np.ndarray
    amp_sigma_px: np.ndarray
    phase_rad: np.ndarray
    phase_sigma_rad: np.ndarray
    sines_px: np.ndarray
    nuisance_px: np.ndarray
    residual_px: np.ndarray
    n_params: int
    basis_coef: np.ndarray


def nuisance_basis(lines: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Columns: 1, the centred line index (the edge's tilt), cos/sin(2 pi h x) for h = 1..3."""
    u = (lines - lines.mean()) / max(np.ptp(lines), 1.0)
    cols = [np.ones_like(u), u]
    for h in range(1, N_PHASE_HARMONICS + 1):
        cols += [np.cos(2 * np.pi * h * positions), np.sin(2 * np.pi * h * positions)]
    return np.stack(cols, axis=1)


def frequency_grid(t: np.ndarray, line_time_s: float) -> np.ndarray:
    """From half a cycle per record to the line-rate Nyquist, ``_OVERSAMPLE`` points per 1 / record."""
    span = float(np.ptp(t)) + line_time_s
    f_nyq = 0.5 / line_time_s
    step = 1.0 / (_OVERSAMPLE * span)
    return np.arange(0.5 / span, f_nyq + 0.5 * step, step)


def periodogram(t, y, basis, freqs):
    """(z, amplitude px) of one sinusoid added at each frequency to the least-squares model ``basis``:
    ``z`` = the fraction of the residual sum of squares it explains."""
    q, _ = np.linalg.qr(basis)
    r = y - q @ (q.T @ y)
    rss0 = float(r @ r)
    z = np.empty(freqs.size)
    amp = np.empty(freqs.size)
    block = max(1, _CHUNK // max(t.size, 1))
    for i in range(0, freqs.size, block):
        arg = 2 * np.pi * t[:, None] * freqs[None, i : i + block]
        s, c = np.sin(arg), np.cos(arg)
        s -= q @ (q.T @ s)
        c -= q @ (q.T @ c)
        ss, cc, sc = (s * s).sum(0), (c * c).sum(0), (s * c).sum(0)
        bs, bc = r @ s, r @ c
        det = ss * cc - sc * sc
        tot = ss + cc
        # near 0 or the Nyquist frequency one column vanishes: fit the other alone
        two = (det > 1e-9 * ss * cc) & (np.minimum(ss, cc) > 1e-6 * tot)
        det = np.where(two, det, 1.0)
        s_only = ~two & (ss > cc)
        a_s = np.where(two, (cc * bs - sc * bc) / det, np.where(s_only, bs / np.maximum(ss, 1e-300), 0.0))
        a_c = np.where(two, (ss * bc - sc * bs) / det, np.where(s_only, 0.0, bc / np.maximum(cc, 1e-300)))
        z[i : i + block] = (a_s * bs + a_c * bc) / max(rss0, 1e-300)
        amp[i : i + block] = np.hypot(a_s, a_c)
    return np.clip(z, 0.0, 1.0), amp, rss0


def baluev_fap(z: float, t: np.ndarray, f_max: float, d_null: int) -> float:
    """Baluev (2008) false-alarm probability of a periodogram maximum ``z`` (standard normalisation) over
    (0, f_max], for a null model of ``d_null`` parameters and an added sinusoid of 2."""
    n = t.size
    nh, nk = n - d_null, n - d_null - 2
    if nk <= 1 or z >= 1.0:
        return 0.0 if z >= 1.0 else 1.0
    fap_single = (1.0 - z) ** (0.5 * nk)
    gamma = np.sqrt(2.0 / nh) * np.exp(gammaln(nh / 2.0) - gammaln((nh - 1) / 2.0))
    w = f_max * np.sqrt(4 * np.pi * np.var(t))
    tau = gamma * w * (1.0 - z) ** (0.5 * (nk - 1)) * np.sqrt(0.5 * nh * z)
    return float(min(1.0, 1.0 - (1.0 - fap_single) * np.exp(-tau)))


def threshold_z(alpha: float, t: np.ndarray, f_max: float, d_null: int) -> float:
    """The periodogram level whose false-alarm probability is ``alpha``."""
    if baluev_fap(1.0 - 1e-12, t, f_max, d_null) > alpha:
        return 1.0
    return float(brentq(lambda z: baluev_fap(z, t, f_max, d_null) - alpha, 1e-12, 1.0 - 1e-12, xtol=1e-12))


def fit_sinusoids(t, y, basis, freqs0) -> SineFit:
    """Nonlinear least squares of ``basis @ c + sum_k (a_k sin + b_k cos)(2 pi f_k t)``, frequencies free,
    from ``freqs0`` (the linear part solved exactly at the start)."""
    k = len(freqs0)
    t_mid = 0.5 * (t.min() + t.max())
    tc = t - t_mid
    span = max(float(np.ptp(t)), 1e-300)
    nb = basis.shape[1]

    def design(fs):
        arg = 2 * np.pi * tc[:, None] * np.asarray(fs)[None, :]
        return np.concatenate([basis, np.sin(arg), np.cos(arg)], axis=1)

    lin0 = np.linalg.lstsq(design(freqs0), y, rcond=None)[0]
    p0 = np.concatenate([lin0, np.asarray(freqs0) * span])

    def split(p):
        return p[: nb + 2 * k], p[nb + 2 * k :] / span

    def resid(p):
        lin, fs = split(p)
        return design(fs) @ lin - y

    def jac(p):
        lin, fs = split(p)
        arg = 2 * np.pi * tc[:, None] * fs[None, :]
        a, b = lin[nb : nb + k], lin[nb + k :]
        dfs = (2 * np.pi * tc[:, None] / span) * (a * np.cos(arg) - b * np.sin(arg))
        return np.concatenate([design(fs), dfs], axis=1)

    sol = least_squares(resid, p0, jac=jac, method="lm", xtol=1e-12, ftol=1e-12, max_nfev=200)
    return _summarise(sol.x, jac(sol.x), -resid(sol.x), (tc, t_mid, span, nb, k, basis))


def _summarise(p, j, res, ctx) -> SineFit:
    """Amplitudes, phases at t = 0 and their 1-sigma from the covariance ``s^2 (J^T J)^-1``."""
    tc, t_mid, span, nb, k, basis = ctx
    n_par = p.size
    s2 = float(res @ res) / max(res.size - n_par, 1)
    cov = s2 * np.linalg.pinv(j.T @ j)
    a, b, fs = p[nb : nb + k], p[nb + k : nb + 2 * k], p[nb + 2 * k :] / span
    amp = np.hypot(a, b)
    phase_c = np.arctan2(b, a)  # a sin + b cos = A sin(arg + phi), A cos phi = a, A sin phi = b
    phase0 = np.mod(phase_c - 2 * np.pi * fs * t_mid + np.pi, 2 * np.pi) - np.pi
    amp_sig, ph_sig, f_sig = np.empty(k), np.empty(k), np.empty(k)
    for i in range(k):
        idx = [nb + i, nb + k + i, nb + 2 * k + i]
        c = cov[np.ix_(idx, idx)]
        ai, bi, aa = a[i], b[i], max(amp[i], 1e-300)
        # (A, phi_0, f) from (a, b, f_scaled): phi_0 = atan2(b, a) - 2 pi f t_mid
        g = np.array(
            [
                [ai / aa, bi / aa, 0.0],
                [-bi / aa**2, ai / aa**2, -2 * np.pi * t_mid / span],
                [0.0, 0.0, 1.0 / span],
            ]
        )
        cc = g @ c @ g.T
        amp_sig[i], ph_sig[i], f_sig[i] = np.sqrt(np.maximum(np.diag(cc), 0.0))
    arg = 2 * np.pi * tc[:, None] * fs[None, :]
    sines = np.sin(arg) @ a + np.cos(arg) @ b
    return SineFit(fs, f_sig, amp, amp_sig, phase0, ph_sig, sines, basis @ p[:nb], res, n_par, p[:nb])
