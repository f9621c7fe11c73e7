"""Slanted-edge checks: MTF at Nyquist along the edge normal, and the edge angle."""

from __future__ import annotations

from typing import Any

import numpy as np

from satchain.comparison._common import NOISE_FLOOR_SIGMAS, finite, rice_mean, sigma_or_why, within
from satchain.comparison.records import CheckRow, EdgeCheck
from satchain.comparison.sigma import edge_angle_sigma
from satchain.prediction.core import Predictions
from satchain.tf.pushbroom_roi import rows_blur_otf

__all__ = ["edge_checks"]


def edge_checks(entries: list[dict], pred: Predictions, tol: Any) -> tuple[list[EdgeCheck], list[CheckRow]]:
    """Slanted edges: MTF at Nyquist (0.5 cy/px along the edge normal) vs the system MTF there, and the angle
    vs the truth -- the truth through the image geometry (``angle_deg_expected``) when the measurement gives one
    (a pushbroom image sheared by Earth rotation or scaled by a line-rate error); sigma from the edge's
    ``mtf_at_nyquist_sigma`` and its angle's position noise."""
    details, rows = [], []
    for e in entries:
        p = pred.edge(e["id"], e["direction"])
        meas = finite(e.get("mtf_at_nyquist"))
        moved, flags = _as_imaged(e, p, pred), list(e.get("flags") or []) + _alt_rows_moved(e, pred)
        p_nyq, run_flags = _compared_prediction(
            e, moved.get("mtf_at_nyquist_predicted_per_row"), p.mtf_at_nyquist, moved, flags
        )
        p_nyq, model = _noise_floor(p_nyq, finite(e.get("mtf_at_nyquist_sigma", e.get("mtf_at_nyquist_std"))), moved)
        err = None if meas is None else meas - p_nyq
        f = np.asarray(e.get("f_cy_per_px", []), float)
        a, a_true = finite(e.get("angle_deg")), finite(e.get("angle_deg_truth"))
        a_los = _angle_through_rows(e, pred)
        geometric = a_los is not None or e.get("angle_deg_expected") is not None
        a_ref = a_los if a_los is not None else finite(e.get("angle_deg_expected")) if geometric else a_true
        a_err = None if a is None or a_ref is None else a - a_ref
        details.append(
            {
                "id": e["id"],
                "direction": e["direction"],
                "normal": list(p.normal),
                "angle_deg": a,
                "angle_deg_truth": a_true,
                "mtf_at_nyquist_measured": meas,
                "mtf_at_nyquist_predicted": p_nyq,
                "mtf_at_nyquist_error": err,
                "pass": within(err, tol.edge_mtf_at_nyquist),
                "rer_measured": finite(e.get("rer")),
                "mtf50_cy_per_px": finite(e.get("mtf50_cy_per_px")),
                "f_cy_per_px": f.tolist(),
                "mtf_measured": e.get("mtf", []),
                "mtf_predicted": p.mtf(f).tolist(),
                "mtf_at_nyquist_sigma": finite(e.get("mtf_at_nyquist_sigma", e.get("mtf_at_nyquist_std"))),
                "mtf_sigma": e.get("mtf_sigma"),
                "flags": flags + run_flags,
                **({"angle_deg_expected": a_ref} if geometric else {}),
                **moved,
            }
        )
        why = None if meas is not None else "the edge gave no MTF at Nyquist"
        sig = sigma_or_why(details[-1]["mtf_at_nyquist_sigma"], err, "the edge measurement gave no MTF sigma")
        rows.append(
            CheckRow(
                f"edge {e['id']} MTF@Nyquist ({e['direction']})", "edge_mtf_at_nyquist", e["id"], meas,
                p_nyq, err, tol.edge_mtf_at_nyquist, f"±{tol.edge_mtf_at_nyquist}",
                within(err, tol.edge_mtf_at_nyquist), why, *sig, model_prediction=model,
                note=_noise_floor_note(details[-1]) or _as_imaged_note(details[-1]),
            )
        )  # fmt: skip
        why = None if a_err is not None else "no measured or true angle"
        sig = sigma_or_why(edge_angle_sigma(e), a_err, "no contrast-to-noise, line count or region for the edge")
        label, note = f"edge {e['id']} angle (deg)", None
        if geometric:
            label = f"edge {e['id']} angle (deg, through the pushbroom image geometry)"
            note = (
                f"measured vs the truth's {a_true:.3f} deg mapped through the pushbroom image geometry (Earth "
                "rotation's shear or yaw, the along-track scale): the angle the image should show"
                if a_true is not None
                else "measured vs the truth mapped through the image geometry"
            )
            if a_los is not None and finite(e.get("angle_deg_expected")) is not None:
                note += (
                    f"; the line of sight moves the rows (mean map alone: {finite(e.get('angle_deg_expected')):.3f} "
                    f"deg), so the prediction is the edge measurement's own fit (degree "
                    f"{int(e.get('fit_degree') or 1)}) of the positions the line-of-sight model puts the edge at on "
                    "the region's lines (the per-line plot 'line_of_sight.png' shows them against the measured ones)"
                )
        rows.append(
            CheckRow(
                label, "edge_angle", e["id"], a, a_ref, a_err, tol.edge_angle_deg,
                f"±{tol.edge_angle_deg}", within(a_err, tol.edge_angle_deg), why, *sig, note=note,
            )
        )  # fmt: skip
    return [EdgeCheck.from_dict(d) for d in details], rows


def _noise_floor(predicted: float, sigma: float | None, moved: dict) -> tuple[float, float | None]:
    """Where the predicted MTF at Nyquist lies within :data:`NOISE_FLOOR_SIGMAS` sigmas of zero (an optics cutoff
    at or below Nyquist, Q >= 2), the measurement reads the magnitude of the MTF plus its noise, never below it:
    the expected reading is the Rice mean of the prediction (:func:`rice_mean`), which the check compares with
    (the model's value kept beside it). Returns ``(compared prediction, model value or None)``."""
    if sigma is None or sigma <= 0 or not abs(predicted) < NOISE_FLOOR_SIGMAS * sigma:
        return predicted, None
    expected = rice_mean(predicted, sigma)
    moved["mtf_at_nyquist_model"] = predicted
    moved["mtf_at_nyquist_noise_floor"] = expected
    return expected, predicted


def _noise_floor_note(d: dict) -> str | None:
    model = d.get("mtf_at_nyquist_model")
    if model is None:
        return None
    return (
        f"the model's MTF at Nyquist ({model:.4f}) is within {NOISE_FLOOR_SIGMAS:g} sigma of 0: the measured "
        f"magnitude of MTF + noise reads {d['mtf_at_nyquist_noise_floor']:.4f} on average (the Rice mean), the "
        "value compared"
    )


def _as_imaged(e: dict, p, pred: Predictions) -> dict:
    """An edge on a pushbroom image whose rows the line of sight displaces: its MTF at Nyquist as imaged (the
    rows' displacements folded in, ISO 12233) measured, and predicted over its region's rows
    (:meth:`satchain.tf.pushbroom.PushbroomTerms.as_imaged_otf` over the budget's per-row terms, on each axis of
    the normal) about a straight edge and about the measurement's own edge polynomial (``fit_degree``: what its
    headline MTF folds in when it does not locate each line), the motion the measurement removed and the rms
    displacement the geometry predicts about a straight edge over the region's rows; {} without such a
    geometry."""
    geo = pred.geometry
    terms, roi = (None if geo is None else geo.terms), e.get("roi_px")
    if geo is None or terms is None or roi is None or not geo.moves:
        return {}
    ratio, ratio_fit, ratio_rows = 1.0, 1.0, 1.0
    span = {"first_line": max(int(roi[1]), 0), "n_lines": int(roi[3]) - max(int(roi[1]), 0)}
    deg = int(min(max(int(e.get("fit_degree") or 1), 1), 3))
    for axis, comp in zip(("act", "alt"), np.abs(np.asarray(p.normal, float)), strict=True):
        if comp > 1e-6:  # lines in time (an ACT edge's rows): about the straight edge; else about the mean
            per = abs(terms.per_row_otf(0.5 * comp, axis)[0])
            kw = {**span, "about_line": e["direction"] == "ACT"}
            img = terms.as_imaged_otf(0.5 * comp, axis, **kw)[0]
            fit = img if deg == 1 else terms.as_imaged_otf(0.5 * comp, axis, **kw, degree=deg)[0]
            own = rows_blur_otf(terms, 0.5 * comp, axis, **span)[0]  # the rows' blur as their paths are
            if per <= 1e-3:
                ratio = ratio_fit = ratio_rows = float("nan")
                continue
            ratio, ratio_fit, ratio_rows = ratio * img / per, ratio_fit * fit / per, ratio_rows * own / per
    rows = np.arange(span["first_line"], min(int(roi[3]), np.asarray(geo.dx_px).size))
    d = np.asarray(geo.dx_px if e["direction"] == "ACT" else geo.dy_px, float)[rows]
    rms = float(np.std(d - np.polyval(np.polyfit(rows, d, 1), rows))) if d.size > 2 else 0.0
    return {
        "mtf_as_imaged_at_nyquist_measured": finite(e.get("mtf_as_imaged_at_nyquist")),
        "los_motion_rms_px": finite(e.get("los_motion_rms_px")),
        "mtf_as_imaged_at_nyquist_predicted": finite(p.mtf_at_nyquist * ratio),
        "mtf_at_nyquist_predicted_per_row": finite(p.mtf_at_nyquist * ratio_rows),
        "mtf_at_nyquist_predicted_as_located": finite(p.mtf_at_nyquist * ratio_fit),
        "los_motion_rms_px_predicted": rms,
        "fit_degree": deg,
    }


#: The run flags an edge whose lines the geometry displaces when its as-imaged and per-row MTFs at Nyquist differ
#: by more than this, or the displacement about a straight edge over its rows exceeds LOS_FLAG_RMS_PX.
LOS_FLAG_MTF = 0.01
LOS_FLAG_RMS_PX = 0.03


def _compared_prediction(e: dict, per_row, budget: float, moved: dict, flags: list) -> tuple[float, list[str]]:
    """The prediction of what the edge's headline MTF at Nyquist measures, and the run's own flags: the per-row
    terms (the blur about each row's position over the region's rows as their paths are, ``per_row``; the
    budget's expectation ``budget`` without a moving geometry) where the measurement located each line (its flag
    ``line_of_sight_motion``: ``mtf_aligned``) or nothing moves the rows; else the MTF as imaged over the
    region's rows about the measurement's own edge polynomial, and flag ``line_of_sight_motion`` when the
    geometry's displacement changes it (more than :data:`LOS_FLAG_MTF` from the per-row MTF, or over
    :data:`LOS_FLAG_RMS_PX` rms) though the measurement saw no motion. An ALT edge flagged
    ``alt_line_of_sight_motion`` keeps the budget's per-row terms (see its note)."""
    located = moved.get("mtf_at_nyquist_predicted_as_located")
    if "alt_line_of_sight_motion" in flags or not moved:
        return budget, []
    if "line_of_sight_motion" in flags or located is None:
        moved["mtf_at_nyquist_compared"] = "aligned"
        return (budget if per_row is None else per_row), []
    moved["mtf_at_nyquist_compared"] = "as_imaged"
    line, ref = moved.get("mtf_as_imaged_at_nyquist_predicted"), budget if per_row is None else per_row
    big = moved["los_motion_rms_px_predicted"] > LOS_FLAG_RMS_PX
    return located, (["line_of_sight_motion"] if big or (line is not None and abs(line - ref) > LOS_FLAG_MTF)
                     else [])  # fmt: skip


def _alt_rows_moved(e: dict, pred: Predictions) -> list[str]:
    """``["alt_line_of_sight_motion"]`` for an ALT edge whose region's rows the line of sight displaces along its
    normal by more than 0.03 px rms (:attr:`ImageGeometry.dy_px`): each of its lines (a column) crosses many
    rows, so the rows' displacements warp the ESF's axis (a local along-track scale) where no line can show them."""
    geo, roi = pred.geometry, e.get("roi_px")
    if geo is None or roi is None or e.get("direction") != "ALT":
        return []
    dy = np.asarray(geo.dy_px, float)[max(int(roi[1]), 0) : int(roi[3])]
    return ["alt_line_of_sight_motion"] if dy.size > 1 and float(np.std(dy)) > 0.03 else []


def _as_imaged_note(d: dict) -> str | None:
    """The MTF row's note for an edge whose lines the line of sight moves: which quantity is compared (aligned:
    each line located; as imaged: the lines' displacements folded in), or an ALT edge whose rows it displaces
    (``alt_line_of_sight_motion``)."""
    if "alt_line_of_sight_motion" in d["flags"]:
        return (
            "an ALT edge whose rows the line of sight displaces along its normal: the displacements warp the ESF's "
            "axis (a local along-track scale and the rows' own blur at their phase) where no line of the edge can "
            "show them; the measured MTF is as imaged, the prediction the budget's per-row terms (not like with "
            "like: measure the motion on a near-vertical edge)"
        )
    how, imaged = d.get("mtf_at_nyquist_compared"), d.get("mtf_as_imaged_at_nyquist_measured")
    if how is None or (how == "aligned" and "line_of_sight_motion" not in d["flags"]):
        return None
    pred, rms = d.get("mtf_as_imaged_at_nyquist_predicted"), d.get("los_motion_rms_px_predicted") or 0.0
    tail = "" if imaged is None else f"as imaged (ISO 12233, one straight edge): measured {imaged:.3f}"
    tail += "" if pred is None else f"{', p' if tail else 'p'}redicted over the region's rows {pred:.3f}"
    if how == "aligned":
        return (
            f"aligned: measured with each line located ({d.get('los_motion_rms_px') or 0:.3f} px rms of "
            "line-of-sight motion removed) vs the per-row motion terms (the blur about each row's position, over "
            "the region's rows as their paths are)" + (f"; {tail}" if tail else "")
        )
    flag = "line_of_sight_motion" in d["flags"]
    moved = f"the geometry displaces the region's lines by {rms:.3f} px rms about a straight edge" + (
        ", below what the measurement could locate line by line (flag line_of_sight_motion)" if flag else ""
    )
    return (
        "as imaged"
        + (f": {moved}" if rms > LOS_FLAG_RMS_PX or flag else "")
        + f"; the headline (the edge located as a degree-{int(d.get('fit_degree') or 1)} curve, the lines' "
        f"displacements about it folded in) vs the MTF as imaged about that curve over the region's rows "
        f"{d['mtf_at_nyquist_predicted']:.3f} (per-row terms over those rows "
        f"{d.get('mtf_at_nyquist_predicted_per_row') or float('nan'):.3f})" + (f"; {tail}" if tail else "")
    )


def _angle_through_rows(e: dict, pred: Predictions) -> float | None:
    """The angle the measurement should give of edge ``e`` on a pushbroom image whose rows the line of sight
    displaces (``pred.geometry``, :class:`satchain.prediction.image_geometry.ImageGeometry`): its fit of the
    positions the geometry predicts on the lines it measured; None without that geometry or those lines."""
    geo = pred.geometry
    if geo is None or not geo.moves or not e.get("lines") or e.get("direction_truth", e["direction"]) != e["direction"]:
        return None  # (straight rows: the mean map's angle; an edge measured across the other axis: the same)
    fit = geo.edge_angle_deg(e["id"], e["lines"], e.get("edge_position_px"), e.get("fit_degree") or 1, e["direction"])
    return finite(fit)
