"""A staggered layout's geometry on the focal plane (``[detector] layout = "staggered"``, issue 32 points 5 and 8):
where array B sits along track from array A, and the TDI count that placement can hold.

Array B samples the ground half a pixel from array A along and across track. Across track that is a shift of
``p/2`` along the lines; along track the two arrays read at the same line clock, so B's centre line sits
``n + 1/2`` rows from A's (it sees the ground ``n + 1/2`` line periods later). An N-stage TDI array is N rows
tall, and two arrays cannot overlap on the focal plane: ``n + 1/2 >= N``, i.e. ``n >= N`` for a whole ``n``.
(Reading one array at twice the line rate instead, the other way to sample half a line, would move the charge
twice per line of image motion and smear its TDI.)
"""

from __future__ import annotations

from typing import Any

__all__ = ["STAGGER_SEPARATION_DOC", "check_stagger_separation", "stagger_separation_px"]

#: ``detector.stagger_separation_px``'s description (the docs' key reference quotes it).
STAGGER_SEPARATION_DOC = (
    "a staggered layout's along-track distance from array A's centre line to array B's, in rows (detector pixels "
    "of pitch_y_m): n + 1/2, so that B samples the ground half a line from A. Each array is tdi_stages rows tall "
    "and the two cannot overlap on the focal plane, so n >= tdi_stages (a TDI count the separation cannot hold is "
    "refused; reading one array at twice the line rate instead would smear its TDI); default: tdi_stages + 1/2, "
    "the closest they fit (the simulation images B half a GSD from A, without the time between them)"
)


def stagger_separation_px(detector: Any) -> float:
    """Array B's centre line from A's along track, rows: ``detector.stagger_separation_px``, or the closest the
    TDI arrays fit, ``tdi_stages + 1/2``.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> stagger_separation_px(SimpleNamespace(stagger_separation_px=None, tdi_stages=8))
    8.5
    """
    s = getattr(detector, "stagger_separation_px", None)
    return float(detector.tdi_stages + 0.5 if s is None else s)


def check_stagger_separation(detector: Any) -> None:
    """Raise ValueError (one line, naming both values) when ``detector.stagger_separation_px`` is given without a
    staggered layout, is not a whole number of rows plus 1/2, or cannot hold ``detector.tdi_stages`` rows."""
    s, n = getattr(detector, "stagger_separation_px", None), int(detector.tdi_stages)
    if s is None:
        return
    if detector.layout != "staggered":
        raise ValueError(f"detector.stagger_separation_px = {s!r}: needs detector.layout = 'staggered'")
    if abs(s % 1.0 - 0.5) > 1e-9:
        raise ValueError(
            f"detector.stagger_separation_px = {s!r}: must be a whole number of rows plus 1/2 (n + 0.5), so that "
            "array B samples the ground half a line from array A"
        )
    if s < n + 0.5 - 1e-9:
        raise ValueError(
            f"detector.stagger_separation_px = {s!r} cannot hold detector.tdi_stages = {n}: two {n}-row TDI arrays "
            f"half a line apart in phase need their centre lines >= {n + 0.5:g} rows apart (they cannot overlap on "
            "the focal plane)"
        )
