"""The diffraction MTF of an annular pupil in closed form (O'Neill 1956) and Shannon's aberration transfer function.

Part of :mod:`satchain.tf.optics`, which re-exports every public name; frequencies are focal-plane cycles per
mm and the incoherent cutoff is ``1 / (lambda F#)``.

Examples
--------
>>> round(float(annular_mtf(50.0, wavelength_m=650e-9, f_number=9.72, obscuration_ratio=0.33)), 4)
0.4353
"""

from __future__ import annotations

import numpy as np

from satchain import units
from satchain._validate import as_float_array, check_positive, check_range

__all__ = ["SHANNON_W0_WAVES", "annular_mtf", "optical_cutoff_cy_per_mm", "shannon_atf"]

SHANNON_W0_WAVES = 0.18  # Shannon's ATF constant (waves rms)


def optical_cutoff_cy_per_mm(wavelength_m: float, f_number: float) -> float:
    """Incoherent diffraction cutoff ``1 / (lambda F#)`` in focal-plane cycles per mm.

    Examples
    --------
    >>> round(optical_cutoff_cy_per_mm(500e-9, 10.0), 6)
    200.0
    """
    lam = check_positive("wavelength_m", wavelength_m)
    return 1.0 / (lam * check_positive("f_number", f_number) * units.MM_PER_M)


def _oneill(v: np.ndarray, eps: float) -> np.ndarray:
    """Normalised annular-pupil MTF at ``v = f / cutoff`` (O'Neill 1956, in Schroeder's notation).

    The three region boundaries (``v = eps``, ``(1 -/+ eps) / 2``) are handled by clipping the arguments
    of ``arccos``: each term then takes its constant value outside its region, so no branch is needed. The
    obscuration's terms are evaluated only inside their regions (``B`` is 0 for ``v >= eps``; ``C`` is
    constant where its ``arccos`` argument is clipped) and take those constants elsewhere.
    """
    v = np.abs(np.asarray(v, dtype=float))
    support = ~(v >= 1.0)  # the MTF is 0 beyond the cutoff: evaluated only inside it (NaN stays NaN)
    if support.all():
        return _oneill_inside(v, eps)
    out = np.zeros(v.shape)
    out[support] = _oneill_inside(v[support], eps)
    return out


def _oneill_inside(v: np.ndarray, eps: float) -> np.ndarray:
    """:func:`_oneill` at ``v = |f| / cutoff`` (>= 0; values at or beyond 1 give 0)."""
    v = np.clip(v, 0.0, 1.0)
    a = (2.0 / np.pi) * (np.arccos(v) - v * np.sqrt(1.0 - v * v))
    if eps == 0.0:
        return np.where(v >= 1.0, 0.0, np.clip(a, 0.0, 1.0))
    b = np.zeros_like(v)
    inner = v < eps
    with np.errstate(over="ignore"):  # a subnormal eps overflows to +-inf, which the clipping handles
        x = np.minimum(v[inner] / eps, 1.0)
        cos_phi = ((1.0 - 2.0 * v) * (1.0 + 2.0 * v) + eps * eps) / (2.0 * eps)
    b[inner] = (2.0 * eps * eps / np.pi) * (np.arccos(x) - x * np.sqrt(1.0 - x * x))
    ring = (cos_phi > -1.0) & (cos_phi < 1.0)
    c = np.where(cos_phi >= 1.0, _oneill_c(np.array(1.0), eps), _oneill_c(np.array(-1.0), eps))
    c[ring] = _oneill_c(cos_phi[ring], eps)
    mtf = (a + b + c) / (1.0 - eps * eps)
    return np.where(v >= 1.0, 0.0, np.clip(mtf, 0.0, 1.0))


def _oneill_c(cos_phi: np.ndarray, eps: float) -> np.ndarray:
    """O'Neill's cross-overlap term ``C`` at ``cos(phi)`` (in [-1, 1])."""
    phi = np.arccos(cos_phi)
    # atan(((1+eps)/(1-eps)) tan(phi/2)) written with arctan2 so that phi = pi gives exactly pi/2
    at = np.arctan2((1.0 + eps) * np.sin(phi / 2.0), (1.0 - eps) * np.cos(phi / 2.0))
    return (
        (2.0 * eps / np.pi) * np.sin(phi)
        + ((1.0 + eps * eps) / np.pi) * phi
        - (2.0 * (1.0 - eps * eps) / np.pi) * at
        - 2.0 * eps * eps
    )


def annular_mtf(f_cy_per_mm, *, wavelength_m: float, f_number: float, obscuration_ratio: float = 0.0):
    """Diffraction MTF of a circular pupil with a central obscuration, in closed form.

    O'Neill, E. L. (1956), "Transfer function for an annular aperture", JOSA 46, 285, in the form given by
    Schroeder, *Astronomical Optics*, 2nd ed. (2000). With ``v = |f| lambda F#``::

        MTF = (A + B + C) / (1 - eps^2),   A = (2/pi) (acos v - v sqrt(1 - v^2))

    ``B`` and ``C`` are the obscuration's self- and cross-overlap terms. For ``eps = 0`` it is the
    circular-pupil MTF ``A``. It equals 1 at f = 0 and exactly 0 at and beyond ``1 / (lambda F#)``.

    Parameters
    ----------
    f_cy_per_mm : array_like
        Radial focal-plane frequency (cy/mm); the sign is ignored.
    wavelength_m, f_number : float
        Wavelength (m) and working F-number.
    obscuration_ratio : float
        Central obscuration diameter / aperture diameter, in [0, 1).

    Returns
    -------
    ndarray of float, the MTF (real and >= 0, so also the OTF).

    Examples
    --------
    >>> float(annular_mtf(0.0, wavelength_m=500e-9, f_number=10.0))
    1.0
    >>> round(float(annular_mtf(100.0, wavelength_m=500e-9, f_number=10.0)), 6)  # v = 0.5
    0.391002
    """
    cutoff = optical_cutoff_cy_per_mm(wavelength_m, f_number)
    eps = check_range("obscuration_ratio", obscuration_ratio, 0.0, 1.0, hi_open=True)
    f = as_float_array("f_cy_per_mm", f_cy_per_mm)
    return _oneill(np.abs(f) / cutoff, eps)


def shannon_atf(f_norm, wfe_rms_waves: float):
    """Shannon's empirical aberration transfer function for a random wavefront error of ``W`` waves rms.

    ``ATF(v) = 1 - (W / 0.18)^2 (1 - 4 (v - 0.5)^2)`` with ``v = |f| / cutoff`` clipped to [0, 1] and the
    result clipped to >= 0 (the fit is meant for W up to about 0.18 waves). Multiply the diffraction MTF
    by it. Shannon, R. R., *The Art and Science of Optical Design* (1997); Fiete, R. D., *Modeling the
    Imaging Chain of Digital Cameras* (2010), the optics chapter.

    Examples
    --------
    >>> shannon_atf([0.0, 0.5, 1.0], 0.09).round(6).tolist()
    [1.0, 0.75, 1.0]
    """
    w = check_range("wfe_rms_waves", wfe_rms_waves, 0.0, None)
    v = np.clip(np.abs(as_float_array("f_norm", f_norm)), 0.0, 1.0)
    return np.clip(1.0 - (w / SHANNON_W0_WAVES) ** 2 * (1.0 - 4.0 * (v - 0.5) ** 2), 0.0, None)
