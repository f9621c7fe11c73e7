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
