"""Check rows of the focal-plane sections (:class:`satchain.comparison.CheckRow`), built one way for all."""

from __future__ import annotations

import math

from satchain.comparison import CheckRow

__all__ = ["check_row", "na_row"]


def _finite(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(float(v)) else float(v)


def check_row(figure: str, kind: str, id_: str | None, measured: float | None, predicted: float | None, *,
              tolerance: float, tolerance_text: str, sigma: float | None, relative: bool = False,
              reason: str | None = None, sigma_null_means: str | None = None,
              note: str | None = None) -> CheckRow:  # fmt: skip
    """A check of ``measured`` against ``predicted``: ``error = measured - predicted`` (``measured / predicted - 1``
    when ``relative``; ``sigma`` in that error's unit), passing when ``|error| <= tolerance``; n/a (``passed``
    None) with ``reason`` when either is missing or not finite."""
    m, p = _finite(measured), _finite(predicted)
    if m is None or p is None or (relative and p == 0):
        why = reason or ("not measured" if m is None else "no prediction")
        return na_row(figure, kind, id_, tolerance=tolerance, tolerance_text=tolerance_text, reason=why,
                      measured=m, predicted=p)  # fmt: skip
    err = m / p - 1 if relative else m - p
    s = _finite(sigma)
    why_no_sigma = None if s is not None else (sigma_null_means or "the measurement gives no uncertainty")
    return CheckRow(figure, kind, id_, m, p, err, tolerance, tolerance_text, bool(abs(err) <= tolerance), None, s,
                    why_no_sigma, note=note)  # fmt: skip


def na_row(figure: str, kind: str, id_: str | None, *, tolerance: float, tolerance_text: str, reason: str,
           measured: float | None = None, predicted: float | None = None) -> CheckRow:  # fmt: skip
    """An n/a check (``passed`` None): ``reason`` says why it could not be made."""
    return CheckRow(figure, kind, id_, measured, predicted, None, tolerance, tolerance_text, None, reason, None,
                    "no error (the check is n/a)")  # fmt: skip
