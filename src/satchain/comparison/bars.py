"""Bar-target checks: measured square-wave CTF vs Coltman's CTF of the system MTF along the modulation axis."""

from __future__ import annotations

from typing import Any

import numpy as np

from satchain.comparison._common import finite, floats, sigma_or_why, within
from satchain.comparison.records import BarCheck, CheckRow
from satchain.measure._keys import AT_NOISE_FLOOR
from satchain.prediction.core import Predictions
from satchain.tf import ctf as _ctf

__all__ = ["BAR_COMPARE_MAX_CY_PER_PX", "bar_checks"]

#: Bar groups finer than this (fewer than 2.5 px per period) are listed but not compared with Coltman's CTF.
#: The bar measurement fits the group at its known period with the phase free (measure/bars/_fit.py), so from
#: 2.5 px per period its CTF no longer depends on where the bars fall on the pixel grid (within 0.03 of
#: Coltman's, up to 0.045 and flagged at integer periods where harmonics alias onto the fitted ones); the
#: sampled max - min used before needed 5 px. The MTF derived from all groups is still plotted.
BAR_COMPARE_MAX_CY_PER_PX = 0.4


def bar_checks(entries: list[dict], pred: Predictions, tol: Any) -> tuple[list[BarCheck], list[CheckRow]]:
    """Bar targets: the largest ``|measured - Coltman|`` CTF along the bars' modulation axis over the groups
    with at least 2.5 px per period; sigma the group's ``ctf_std``."""
    details, rows = [], []
    for b in entries:
        m = pred.mtf_along["ALT" if str(b.get("direction", "ACT")).upper() == "ALT" else "ACT"]
        f = np.asarray(b["f_cy_per_px"], float)
        meas = np.array([np.nan if v is None else v for v in b["ctf"]], float)
        col = np.asarray(_ctf.coltman_ctf(f, m), float)
        placed = _at_placement(b, pred, f.size)
        ref = col if placed is None else placed
        std = np.array(floats(b.get("ctf_std"), f.size), float)
        corr = np.array(floats(b.get("ctf_correction"), f.size), float)
        ok = np.isfinite(meas) & np.isfinite(ref) & (f <= BAR_COMPARE_MAX_CY_PER_PX)
        err, i = None, None
        if ok.any():
            i = int(np.flatnonzero(ok)[np.argmax(np.abs(meas[ok] - ref[ok]))])
            err = float(abs(meas[i] - ref[i]))
        groups = _design_indices(b, f.size)
        details.append(
            {
                "id": b["id"],
                "compared_up_to_cy_per_px": BAR_COMPARE_MAX_CY_PER_PX,
                "direction": b.get("direction"),
                "f_cy_per_px": f.tolist(),
                "ctf_measured": meas.tolist(),
                "ctf_coltman_predicted": col.tolist(),
                "ctf_fourier_synthesis_predicted": np.asarray(_ctf.ctf_fourier_synthesis(f, m)).tolist(),
                "mtf_from_ctf_measured": [np.nan if v is None else float(v) for v in b.get("mtf", [None] * f.size)],
                "mtf_predicted": np.asarray(m(f)).tolist(),
                "max_abs_error": err,
                "pass": within(err, tol.bar_ctf),
                "ctf_std_measured": std.tolist(),
                "ctf_correction": corr.tolist(),
                "flags": [str(x) for x in b.get("flags", [])],
                "ctf_raw_measured": np.where(np.isfinite(corr), meas - corr, meas).tolist(),
                "max_abs_error_sigma": None if i is None else finite(std[i]),
                "worst_f_cy_per_px": None if i is None else float(f[i]),
                "group": groups,
                "at_noise_floor": [_at_floor(b.get("flags"), k) for k in groups],
                "worst_group": None if i is None else groups[i],
                **({} if placed is None else {"ctf_predicted_at_placement": placed.tolist()}),
            }
        )
        lim = BAR_COMPARE_MAX_CY_PER_PX
        why = None if err is not None else f"no group with >= {1 / lim:g} px per period (<= {lim} cy/px)"
        sig = sigma_or_why(details[-1]["max_abs_error_sigma"], err, "the bar measurement gave no CTF sigma")
        note = None if i is None else (
            f"largest error at group {groups[i]} ({f[i]:.3f} cy/px, period {1 / f[i]:.2f} px): CTF measured "
            f"{meas[i]:.3f}, " + ("Coltman" if placed is None else "predicted at the image's placement")
            + f" {ref[i]:.3f}" + (" (at the noise floor)" if _at_floor(b.get("flags"), groups[i]) else "")
            + ("" if placed is None else f" (Coltman {col[i]:.3f}); {PLACEMENT_NOTE}")
        )  # fmt: skip
        how = "Coltman" if placed is None else "at the image's placement"
        rows.append(
            CheckRow(
                f"bars {b['id']} max |CTF error| ({how})", "bar_ctf", b["id"], err, 0.0, err, tol.bar_ctf,
                f"≤{tol.bar_ctf}", within(err, tol.bar_ctf), why, *sig, note=note,
            )
        )  # fmt: skip
    return [BarCheck.from_dict(d) for d in details], rows


#: What the bars' check compares on a pushbroom image (:mod:`satchain.prediction.bars`).
PLACEMENT_NOTE = (
    "the prediction is the bar measurement on a noise-free image of the target formed where the pushbroom "
    "geometry puts each row (its line-of-sight displacement: the group's sampling phase and the rows' "
    "displacements over it), through the system MTF with the motion blur those rows have as their paths are "
    "(under Earth rotation a slow oscillation's velocity lengthens or shortens the drift's smear), not the "
    "budget's expectation over the motion's phases"
)


def _at_placement(b: dict, pred: Predictions, n: int) -> np.ndarray | None:
    """The CTF of each of the ``n`` groups measured on the noise-free image of the target at the image's own
    placement (:func:`satchain.prediction.bars.predict_bar_ctf`) for a pushbroom run's image (``pred.geometry``)
    whose line of sight moves the rows along the bars' modulation axis (the rows' displacements and their own
    blur, not the budget's expectation, are what a group a few rows tall shows); None otherwise (Coltman's CTF
    of the system MTF is compared)."""
    geo = pred.geometry
    d = None if geo is None else geo.dy_px if str(b.get("direction", "ACT")).upper() == "ALT" else geo.dx_px
    if geo is None or d is None or float(np.ptp(np.asarray(d, float))) <= 1e-6:
        return None
    from satchain.prediction.bars import predict_bar_ctf

    ctf = predict_bar_ctf(geo, b, pred.mtf_along, geo.background)
    return None if ctf is None or ctf.size != n else ctf


def _design_indices(b: dict, n: int) -> list[int]:
    """Each measured group's index in the target's design (``groups[].group`` of ``measure auto``; 0..n-1 for a
    measurement without them)."""
    rows = b.get("groups") or []
    if len(rows) == n and all(g.get("group") is not None for g in rows):
        return [int(g["group"]) for g in rows]
    return list(range(n))


def _at_floor(flags, k: int) -> bool:
    """Group ``k`` was measured at the noise floor (its CTF ~0 with its 1-sigma is a result)."""
    return any(str(f).startswith(f"group {k}: {AT_NOISE_FLOOR}") for f in flags or ())
