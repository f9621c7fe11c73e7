"""Small helpers the per-kind check builders share: finite floats, the inclusive tolerance test, sigma or why."""

from __future__ import annotations

import math

import numpy as np

#: Why a prediction carries no sigma: it is computed from the very system model the image was simulated with.
PREDICTION_SIGMA_NOTE = "the prediction is exact for the simulated system model (its sigma is 0)"


def finite(v) -> float | None:
    """A finite float, or None (missing, None, NaN or inf)."""
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def within(error: float | None, tolerance: float) -> bool | None:
    """``|error| <= tolerance`` (inclusive); None when there is no error (the check is n/a)."""
    return None if error is None else bool(abs(error) <= tolerance)


def sigma_or_why(sigma: float | None, error: float | None, why: str) -> tuple[float | None, str | None]:
    """``(sigma, None)``, or ``(None, reason)`` when there is no error to qualify or no finite sigma. The
    prediction adds nothing: it is exact for the simulated model (:data:`PREDICTION_SIGMA_NOTE`)."""
    if error is None:
        return None, "no error (the check is n/a)"
    sigma = finite(sigma)
    if sigma is None or sigma < 0:
        return None, why
    return sigma, None


def floats(values, n: int) -> list:
    """A per-point list as floats (NaN where absent)."""
    if values is None:
        return [np.nan] * n
    return [np.nan if v is None else float(v) for v in values]


#: below this many sigmas a predicted MTF is compared with the magnitude its noise gives (:func:`rice_mean`)
NOISE_FLOOR_SIGMAS = 3.0


def rice_mean(nu: float, sigma: float) -> float:
    """The mean of ``|nu + n|`` for a complex Gaussian ``n`` of standard deviation ``sigma`` per component (the
    Rice distribution; Rice 1944): what an MTF measured as the magnitude of a noisy transform reads on average
    where the true MTF is ``nu``. ``nu = 0`` gives the Rayleigh mean ``sigma sqrt(pi / 2)``; for ``nu >> sigma``
    it tends to ``nu + sigma**2 / (2 nu)``.

    Examples
    --------
    >>> round(rice_mean(0.0, 1.0), 6) == round((np.pi / 2) ** 0.5, 6)
    True
    >>> abs(rice_mean(10.0, 1.0) - (10.0 + 1 / 20)) < 1e-3
    True
    """
    from scipy.special import i0e, i1e

    if sigma <= 0:
        return abs(nu)
    u = nu * nu / (4.0 * sigma * sigma)
    return float(sigma * math.sqrt(math.pi / 2.0) * ((1.0 + 2.0 * u) * i0e(u) + 2.0 * u * i1e(u)))
