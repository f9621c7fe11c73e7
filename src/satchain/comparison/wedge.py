"""Hyperbolic-wedge checks: resolvable line width measured vs the same crossing on the noise-free predicted image."""

from __future__ import annotations

from typing import Any

from satchain.comparison._common import finite, within
from satchain.comparison.records import CheckRow, WedgeCheck
from satchain.prediction.core import WEDGE_AXES, Predictions

__all__ = ["wedge_checks"]


def _wedge_sigma(res, pr, p, sd_measure) -> tuple[float | None, float | None, str | None]:
    """(1-sigma of the measured crossing in m, 1-sigma of ``res / pr - 1``, why None).

    The crossing's 1-sigma from noise is the prediction's parametric bootstrap (the predicted image re-measured
    with the sensor's noise added), else the measurement's own estimate. The prediction is made at the image's
    own placement on the pixel grid, which the run knows exactly, so the spread over placements is reported
    beside it (``resolution_predicted_m_std``) and not added."""
    sd = None if p is None else finite(p.resolution_noise_m_std)
    sd = sd_measure if sd is None else sd
    if res is None or pr is None:
        return sd, None, "no relative error (a resolution is missing)"
    if sd is None:
        return None, None, "no noise model (no sensor) and no uncertainty from the measurement"
    return sd, sd / pr, None


def wedge_checks(entries: list[dict], pred: Predictions, tol: Any) -> tuple[list[WedgeCheck], list[CheckRow]]:
    """Hyperbolic wedges: ``measured / predicted - 1`` of the resolvable line width, the prediction being the
    same 15 % crossing measured on the wedge's noise-free predicted image."""
    details, rows = [], []
    for w in entries:
        axis = WEDGE_AXES[w["orientation"]]
        p = pred.wedges.get(str(w["id"]))
        res, pr = finite(w.get("resolution_m")), None if p is None else finite(p.resolution_m)
        sd_measure, sd_pred = finite(w.get("resolution_m_std")), None if p is None else finite(p.resolution_m_std)
        rel = None if res is None or pr is None else res / pr - 1.0
        sd_noise, sigma, sigma_why = _wedge_sigma(res, pr, p, sd_measure)
        pos = w.get("position_m_along_wedge")
        c_pred = None if p is None or pos is None else p.contrast_at(pos).tolist()
        details.append(
            {
                "id": w["id"],
                "orientation": w["orientation"],
                "axis": axis,
                "resolution_m": res,
                "resolution_predicted_m": pr,
                "gsd_m": None if p is None else p.gsd_m,
                "resolution_over_gsd": None if res is None or p is None else res / p.gsd_m,
                "relative_error": rel,
                "pass": within(rel, tol.wedge_resolution_rel),
                "threshold": w.get("threshold"),
                "position_m": pos,
                "contrast": w.get("contrast"),
                "contrast_predicted": c_pred,
                "line_width_m": w.get("line_width_m"),
                "resolution_m_std": sd_noise,
                "resolution_m_std_measure": sd_measure,
                "resolution_predicted_m_std": sd_pred,
                "resolution_predicted_by_placement_m": None if p is None else list(p.resolutions_by_placement_m),
                "relative_error_sigma": sigma,
            }
        )
        why = None
        if res is None:
            why = "the wedge gave no resolution (its contrast never crossed the threshold inside it)"
        elif p is None:
            why = f"no prediction for wedge {w['id']!r} (not in the truth record given to predict)"
        elif pr is None:
            why = "no predicted resolution: " + (p.reason or "the predicted contrast never falls to the threshold")
        rows.append(
            CheckRow(
                f"wedge {w['id']} resolution (m, {axis})", "wedge_resolution", w["id"], res, pr, rel,
                tol.wedge_resolution_rel, f"±{tol.wedge_resolution_rel:.0%}", within(rel, tol.wedge_resolution_rel),
                why, sigma, sigma_why,
            )
        )  # fmt: skip
    return [WedgeCheck.from_dict(d) for d in details], rows
