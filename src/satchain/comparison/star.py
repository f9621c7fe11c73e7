"""Siemens-star checks: the measured MTF per direction vs the same measurement on the noise-free predicted image.

The prediction is :class:`satchain.prediction.star.StarPrediction` (the star measured on its noise-free predicted
image); without one (a :class:`~satchain.prediction.core.Predictions` made without a truth star) the system MTF
along each direction is compared, as before the prediction was measured. The system MTF is kept beside the
prediction (``mtf_model``): their difference is the estimator's systematic, reported, not part of the error.

The error is the largest ``measured - predicted`` (with its sign) over the directions and the frequencies
0.05..0.5 cy/px, so its 1-sigma is that of a maximum: :func:`max_error_sigma` of the points' 1-sigma.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.integrate import trapezoid
from scipy.special import erf

from satchain.comparison._common import PREDICTION_SIGMA_NOTE, finite, floats, within
from satchain.comparison.records import CheckRow, StarCheck
from satchain.prediction.core import NYQUIST_CY_PER_PX, Predictions

__all__ = ["STAR_F_MIN_CY_PER_PX", "max_error_sigma", "star_checks"]

#: The star's MTF is compared from this frequency (cy/px) up to Nyquist.
STAR_F_MIN_CY_PER_PX = 0.05


def max_error_sigma(sigmas) -> float | None:
    """The 1-sigma (root mean square) of the signed error of largest magnitude among independent zero-mean
    normal errors of 1-sigma ``sigmas``: ``sqrt(E[M^2])`` with ``M = max |e_i|``,
    ``E[M^2] = int_0^inf 2 m (1 - prod_i erf(m / (sigma_i sqrt 2))) dm``. Its sign is as likely + as -, so
    this is the spread of the signed error about 0. Sigmas that are not finite and positive are left out;
    None when none is left. (Neighbouring annuli share pixels, so the errors are somewhat correlated and this
    is a little larger than the truth: on the conservative side.)

    Examples
    --------
    >>> round(max_error_sigma([0.01]), 6)  # one point: its own sigma
    0.01
    >>> 1.5 < max_error_sigma([1.0] * 20) < 2.5  # the largest of 20: about 2 sigma
    True
    """
    s = np.asarray([v for v in np.ravel(np.asarray(sigmas, dtype=float)) if np.isfinite(v) and v > 0])
    if s.size == 0:
        return None
    m = np.linspace(0.0, s.max() * (6.0 + np.sqrt(2.0 * np.log(s.size))), 4001)[1:]
    with np.errstate(divide="ignore"):
        log_cdf = np.sum(np.log(erf(m[:, None] / (s[None, :] * np.sqrt(2.0)))), axis=1)
    tail = 1.0 - np.exp(log_cdf)  # P(M > m)
    return float(np.sqrt(trapezoid(2.0 * m * tail, m)))


def _worst(x: np.ndarray, ok: np.ndarray) -> int | None:
    """Index of the largest |x| over ``ok``, or None."""
    return int(np.flatnonzero(ok)[np.argmax(np.abs(x[ok]))]) if ok.any() else None


def _star_direction(f: np.ndarray, curve, std, pred: np.ndarray, model: np.ndarray) -> dict[str, Any]:
    """One direction: the largest |measured - predicted| over STAR_F_MIN..Nyquist with its sign, where, the
    measured, predicted and modelled MTF there and the measurement's 1-sigma; the estimator's systematic
    (predicted - model) at its largest; ``_sigmas``: the compared points' 1-sigma (not written)."""
    meas = np.array([np.nan if v is None else v for v in curve], float)
    sd = np.array(floats(std, f.size), float)
    band = (f >= STAR_F_MIN_CY_PER_PX) & (f <= NYQUIST_CY_PER_PX)
    ok = np.isfinite(meas) & np.isfinite(pred) & band
    out: dict[str, Any] = {
        "mtf_predicted": pred.tolist(),
        "mtf_model": model.tolist(),
        "max_abs_error_to_nyquist": None,
        "_sigmas": sd[ok],
    }
    i = _worst(meas - pred, ok)
    if i is not None:
        out.update(
            max_abs_error_to_nyquist=float(abs(meas[i] - pred[i])),
            error=float(meas[i] - pred[i]),
            worst_f_cy_per_px=float(f[i]),
            max_abs_error_sigma=finite(sd[i]),
            measured=float(meas[i]),
            predicted=float(pred[i]),
            model=float(model[i]),
        )
    j = None if pred is model else _worst(pred - model, np.isfinite(pred) & band)  # no systematic without a prediction
    if j is not None:
        out.update(estimator_systematic=float(pred[j] - model[j]), estimator_systematic_f_cy_per_px=float(f[j]))
    k = _worst(meas - model, np.isfinite(meas) & band)
    out["max_abs_error_to_model"] = None if k is None else float(abs(meas[k] - model[k]))
    return out


def _prediction_text(sp, measured_m0_from) -> str:
    if sp is None:
        return "the system MTF along each direction (no star prediction was made)"
    if sp.reason is not None:
        return f"the system MTF along each direction ({sp.reason})"
    cal = sp.calibration or {}
    text = "the star measured on its noise-free predicted image"
    if cal.get("offset") is not None:
        text += f" (calibrated the way the image is: fitted offset {cal['offset']:+.4f}, gain {cal['gain']:.4f})"
    if measured_m0_from and sp.input_modulation_from and measured_m0_from != sp.input_modulation_from:
        text += (
            f"; its input modulation is {sp.input_modulation_from}, the measured star's "
            f"{measured_m0_from}: the settings differ"
        )
    return text


def _star_detail(st: dict, pred: Predictions, tol: Any) -> tuple[dict[str, Any], int]:
    """The star's record (as :class:`StarCheck` reads it) and how many points were compared."""
    f = np.asarray(st["f_cy_per_px"], float)
    stds = st.get("mtf_std") or {}
    sp = pred.stars.get(str(st["id"]))
    own = sp if sp is not None and sp.reason is None else None  # the star's own predicted image, when made
    per_dir = {}
    for d, curve in st.get("mtf", {}).items():
        model = np.asarray(pred.mtf_along[d.upper()](f), float)
        per_dir[d] = _star_direction(f, curve, stds.get(d), own.mtf_at(d, f) if own is not None else model, model)
    sigmas = np.concatenate([v.pop("_sigmas") for v in per_dir.values()] or [np.zeros(0)])
    done = {d: v for d, v in per_dir.items() if v["max_abs_error_to_nyquist"] is not None}
    wd = max(done, key=lambda d: done[d]["max_abs_error_to_nyquist"]) if done else None
    w = done.get(wd, {})
    sys_d = [d for d, v in per_dir.items() if v.get("estimator_systematic") is not None]
    sys_dir = max(sys_d, key=lambda d: abs(per_dir[d]["estimator_systematic"])) if sys_d else None
    to_model = [v["max_abs_error_to_model"] for v in per_dir.values() if v["max_abs_error_to_model"] is not None]
    worst = w.get("max_abs_error_to_nyquist")
    return {
        "id": st["id"],
        "directions": per_dir,
        "max_abs_error_to_nyquist": worst,
        "pass": within(worst, tol.star_mtf),
        "f_cy_per_px": f.tolist(),
        "mtf_measured": st.get("mtf", {}),
        "max_abs_error_sigma": w.get("max_abs_error_sigma"),
        "worst_direction": wd,
        "worst_f_cy_per_px": w.get("worst_f_cy_per_px"),
        "mtf_std_measured": {d: floats(v, f.size) for d, v in stds.items()},
        "flags": [str(x) for x in st.get("flags", [])],
        "error": w.get("error"),
        "error_sigma": max_error_sigma(sigmas) if w.get("max_abs_error_sigma") is not None else None,
        "measured_at_worst": w.get("measured"),
        "predicted_at_worst": w.get("predicted"),
        "model_at_worst": w.get("model"),
        "estimator_systematic": None if sys_dir is None else per_dir[sys_dir]["estimator_systematic"],
        "estimator_systematic_direction": sys_dir,
        "estimator_systematic_f_cy_per_px": None
        if sys_dir is None
        else per_dir[sys_dir]["estimator_systematic_f_cy_per_px"],
        "max_abs_error_to_model": max(to_model) if to_model else None,
        "prediction": _prediction_text(sp, st.get("input_modulation_from")),
    }, int(sigmas.size)


def _note(d: dict[str, Any], n_points: int) -> str | None:
    """The row's note: where the error is, what was predicted, the estimator's systematic, what sigma is."""
    if d["error"] is None:
        return None
    text = f"largest error at {d['worst_direction']}, {d['worst_f_cy_per_px']:.3f} cy/px; predicted: {d['prediction']}"
    if d["estimator_systematic"] is not None and d["model_at_worst"] is not None:
        text += (
            f"; system MTF there {d['model_at_worst']:.4f}; estimator systematic (predicted - system MTF) "
            f"{d['predicted_at_worst'] - d['model_at_worst']:+.4f} there, largest "
            f"{d['estimator_systematic']:+.4f} ({d['estimator_systematic_direction']}, "
            f"{d['estimator_systematic_f_cy_per_px']:.3f} cy/px); largest |measured - system MTF| "
            f"{d['max_abs_error_to_model']:.4f}"
        )
    text += f"; sigma: of the largest of {n_points} errors, from the measured 1-sigma per point"
    text += f"; {PREDICTION_SIGMA_NOTE}"
    return text


def star_checks(entries: list[dict], pred: Predictions, tol: Any) -> tuple[list[StarCheck], list[CheckRow]]:
    """Siemens stars: the largest ``measured - predicted`` MTF (signed) over the directions and 0.05..0.5 cy/px,
    ``|error| <= star_mtf``; sigma: :func:`max_error_sigma` of the compared points' measured 1-sigma."""
    details, rows = [], []
    for st in entries:
        d, n_points = _star_detail(st, pred, tol)
        details.append(d)
        err = d["error"]
        why = None if err is not None else f"no finite star MTF between {STAR_F_MIN_CY_PER_PX} and 0.5 cy/px"
        sig, sig_why = d["error_sigma"], None
        if err is None:
            sig_why = "no error (the check is n/a)"
        elif sig is None:
            sig_why = "the star measurement gave no MTF sigma at the worst frequency"
        rows.append(
            CheckRow(
                f"star {st['id']} MTF, largest error to Nyquist", "star_mtf", st["id"], d["measured_at_worst"],
                d["predicted_at_worst"], err, tol.star_mtf, f"≤{tol.star_mtf}", within(err, tol.star_mtf), why,
                sig, sig_why, d["model_at_worst"], _note(d, n_points),
            )
        )  # fmt: skip
    return [StarCheck.from_dict(d) for d in details], rows
