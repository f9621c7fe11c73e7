"""The staggered section's checks (:mod:`satchain.focal.staggered`): edges at both Nyquists and bar groups on the
combined grid, against the system MTF times the combination's transfer function."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from satchain.comparison._common import NOISE_FLOOR_SIGMAS, finite, rice_mean
from satchain.comparison.bars import BAR_COMPARE_MAX_CY_PER_PX
from satchain.focal._rows import check_row, na_row
from satchain.measure._keys import AT_NOISE_FLOOR
from satchain.prediction.core import DIRECTIONS, AxisMTF, system_mtf_cy_per_px
from satchain.tf import ctf as _ctf
from satchain.tf.staggered import combination_otf
from satchain.units import MM_PER_M

__all__ = ["CombinedMTF", "bar_section", "combined_mtf2d", "edge_section", "prediction_curves"]

#: Where the edges are read, in cycles per combined pixel: the combined grid's Nyquist (1/p on the focal plane)
#: and one array's (1/(2p)).
AT = (("combined_nyquist", 0.5), ("single_nyquist", 0.25))


class CombinedMTF:
    """The predicted MTF of the combined grid as a callable of ``(fx, fy)`` in cycles per combined pixel (``p/2``):
    the system MTF (``base``, a callable of cycles per array pixel, :func:`satchain.prediction.core.
    system_mtf_cy_per_px`) times the combination's transfer function at ``f = 2 f_c / p``; ``cutoff`` (cy per
    combined px) is half the system's in cy per array px."""

    def __init__(self, base, pitch_m: float):
        self._base = base
        self.pitch_m = float(pitch_m)
        self._p_mm = self.pitch_m * MM_PER_M
        cutoff = getattr(base, "cutoff", None)
        if cutoff is not None:
            self.cutoff = float(cutoff) / 2

    def __call__(self, fx_cy_per_px, fy_cy_per_px) -> np.ndarray:
        fx, fy = 2 * np.asarray(fx_cy_per_px, float), 2 * np.asarray(fy_cy_per_px, float)  # cy per array px
        h = combination_otf(fx / self._p_mm, fy / self._p_mm, pitch_m=self.pitch_m)
        return np.abs(np.asarray(self._base(fx, fy))) * np.abs(h)


def combined_mtf2d(otf, pitch_m: float) -> CombinedMTF:
    """The combined grid's MTF from the run's :class:`~satchain.tf.budget.SystemOTF` (as the run predicts its
    targets: the local MTF, without the aerosol adjacency's plateau)."""
    return CombinedMTF(system_mtf_cy_per_px(otf, local=True), pitch_m)


def prediction_curves(mtf2d: CombinedMTF, pitch_m: float, n: int = 151) -> dict[str, Any]:
    """The predicted combined MTF along ACT and ALT up to 1.5/p (cy/mm on the focal plane), for the figure."""
    p_mm = pitch_m * MM_PER_M
    f_mm = np.linspace(0.0, 1.5 / p_mm, n)
    f_px = f_mm * p_mm / 2
    out: dict[str, Any] = {"f_cy_per_mm": f_mm.tolist()}
    for d, u in DIRECTIONS.items():
        if d in ("ACT", "ALT"):
            out[d.lower()] = AxisMTF(mtf2d, u)(f_px).tolist()
    return out


def _floored(predicted: float, sigma: float | None) -> tuple[float, float | None]:
    """The compared prediction where noise lifts a measured MTF near 0 (the Rice mean, as the run's edge check
    does: :func:`satchain.comparison.edge._noise_floor`), and the model's own value (or None)."""
    if sigma is None or sigma <= 0 or not abs(predicted) < NOISE_FLOOR_SIGMAS * sigma:
        return predicted, None
    return rice_mean(predicted, sigma), predicted


def _at(f: np.ndarray, values, f0: float) -> float | None:
    v = np.asarray([np.nan if x is None else float(x) for x in (values or [])], float)
    if v.size != f.size or f.size < 2 or not f[0] <= f0 <= f[-1]:
        return None
    return finite(np.interp(f0, f, v))


def edge_section(entries: list[dict], truth: dict, mtf2d: CombinedMTF, tol) -> tuple[list, list[dict]]:
    """Each edge measured on the combined grid: rows ``staggered_edge_mtf_at_nyquist`` (combined Nyquist) and
    ``staggered_edge_mtf_at_single_nyquist``, and its data (curves on the focal plane, cy/mm)."""
    normals = {str(it["id"]): it.get("normal_to_bright") for it in truth.get("items", [])}
    p_mm = mtf2d.pitch_m * MM_PER_M
    rows, out = [], []
    for e in entries:
        ident, direction = str(e["id"]), str(e.get("direction", "ACT"))
        n = normals.get(ident) or DIRECTIONS.get(direction, (1.0, 0.0))
        m = AxisMTF(mtf2d, (float(n[0]), float(n[1])))
        f = np.asarray(e.get("f_cy_per_px", []), float)
        d: dict[str, Any] = {"id": ident, "direction": direction, "normal": [m.ux, m.uy], "flags": e.get("flags", []),
                             "f_cy_per_mm": (f * 2 / p_mm).tolist(), "mtf_measured": e.get("mtf", []),
                             "mtf_predicted": m(f).tolist(), "mtf_sigma": e.get("mtf_sigma")}  # fmt: skip
        for key, f0 in AT:
            if key == "combined_nyquist":
                meas, sig = finite(e.get("mtf_at_nyquist")), finite(e.get("mtf_at_nyquist_sigma"))
            else:
                meas, sig = _at(f, e.get("mtf"), f0), _at(f, e.get("mtf_sigma"), f0)
            pred, model = _floored(float(m(f0)), sig)
            kind = "staggered_edge_mtf_at_" + ("nyquist" if key == "combined_nyquist" else "single_nyquist")
            label = "combined Nyquist" if key == "combined_nyquist" else "one array's Nyquist"
            row = check_row(f"staggered edge {ident} MTF@{label} ({direction})", kind, ident, meas, pred,
                            tolerance=tol.edge_mtf_at_nyquist, tolerance_text=f"±{tol.edge_mtf_at_nyquist}",
                            sigma=sig, reason=None if meas is not None else "the edge gave no MTF there",
                            sigma_null_means="the edge measurement gave no MTF sigma",
                            note=None if model is None else _floor_note(model, pred))  # fmt: skip
            if model is not None:
                row = dataclasses.replace(row, model_prediction=model)
            rows.append(row)
            d[key] = {"f_cy_per_mm": f0 * 2 / p_mm, "measured": meas, "predicted": pred, "model": model,
                      "sigma": sig, "error": row.error, "pass": row.passed}  # fmt: skip
        out.append(d)
    return rows, out


def _floor_note(model: float, compared: float) -> str:
    return (
        f"the model's MTF there ({model:.4f}) is within {NOISE_FLOOR_SIGMAS:g} sigma of 0: the measured magnitude of "
        f"MTF + noise reads {compared:.4f} on average (the Rice mean), the value compared"
    )


def _group(b: dict, k: int, f: float, meas: float, std: float, pred: float, thr: float, tol: float,
           p_mm: float) -> dict[str, Any]:  # fmt: skip
    """One bar group on the combined grid: its period in one array's pixels, CTF measured and predicted, whether
    one array could sample it and whether the combination resolves it (CTF >= ``thr``) as predicted."""
    groups = b.get("groups") or []
    g = groups[k] if k < len(groups) else {}
    f_single = 2 * f  # cycles per array pixel
    index = int(g.get("group", k))
    floor = any(str(x).startswith(f"group {index}: {AT_NOISE_FLOOR}") for x in b.get("flags") or ())
    compared = bool(math.isfinite(meas) and math.isfinite(pred) and f <= BAR_COMPARE_MAX_CY_PER_PX and not floor)
    err = float(meas - pred) if compared else None
    res_m, res_p = bool(math.isfinite(meas) and meas >= thr and not floor), bool(pred >= thr)
    alias = abs(1.0 - f_single) if f_single > 0.5 else None
    why = None if compared else (
        "at the measurement's noise floor: its modulation is not above 5 sigma of the noise (on the combined grid "
        "also the quincunx fill's own pattern)" if floor
        else f"finer than {1 / BAR_COMPARE_MAX_CY_PER_PX:g} combined px per period" if f > BAR_COMPARE_MAX_CY_PER_PX
        else "no CTF measured"
    )  # fmt: skip
    return {
        "group": index,
        "not_compared": why,
        "at_noise_floor": floor,
        "period_m": finite(g.get("period_m")),
        "period_single_px": 1 / f_single,
        "period_combined_px": 1 / f,
        "f_cy_per_mm": f * 2 / p_mm,
        "ctf_measured": finite(meas),
        "ctf_std": finite(std),
        "ctf_predicted": float(pred),
        "error": err,
        "compared": compared,
        "beyond_single_nyquist": bool(f_single > 0.5),
        "single_alias_period_px": None if not alias else 1 / alias,
        "resolved_measured": res_m,
        "resolved_predicted": res_p,
        "resolved_as_predicted": bool(
            compared and abs(err or 0.0) <= tol and (res_m == res_p or abs(pred - thr) <= tol)
        ),
    }


def bar_section(entries: list[dict], mtf2d: CombinedMTF, config, *, pitch_m: float) -> tuple[list, list[dict]]:
    """Each bar target on the combined grid: per group the CTF against Coltman's CTF of the combined MTF along the
    bars' axis; a row ``staggered_bar_ctf`` with the largest |error| over the groups compared (>= 2.5 combined px
    per period, as the run's bars check)."""
    tol, thr = float(config.tolerances.bar_ctf), float(config.measurement.wedge_threshold)
    p_mm = pitch_m * MM_PER_M
    rows, out = [], []
    for b in entries:
        ident, direction = str(b["id"]), "ALT" if str(b.get("direction", "ACT")).upper() == "ALT" else "ACT"
        m = AxisMTF(mtf2d, DIRECTIONS[direction])
        f = np.asarray(b.get("f_cy_per_px", []), float)
        meas = np.asarray([np.nan if v is None else v for v in b.get("ctf", [])], float)
        std = np.asarray([np.nan if v is None else v for v in (b.get("ctf_std") or [None] * f.size)], float)
        pred = np.asarray(_ctf.coltman_ctf(f, m), float) if f.size else np.zeros(0)
        groups = [_group(b, k, f[k], meas[k], std[k], pred[k], thr, tol, p_mm) for k in range(f.size)]
        done = [g for g in groups if g["compared"]]
        worst = max(done, key=lambda g: abs(g["error"])) if done else None
        out.append({"id": ident, "direction": direction, "groups": groups, "flags": b.get("flags", []),
                    "max_abs_error": None if worst is None else abs(worst["error"]),
                    "worst_group": None if worst is None else worst["group"]})  # fmt: skip
        lim = BAR_COMPARE_MAX_CY_PER_PX
        figure = f"staggered bars {ident} max |CTF error| (Coltman, combined grid, {direction})"
        if worst is None:
            why = f"no group with >= {1 / lim:g} combined px per period (<= {lim} cy/px)"
            rows.append(na_row(figure, "staggered_bar_ctf", ident, tolerance=tol, tolerance_text=f"≤{tol}", reason=why))
            continue
        rows.append(check_row(figure, "staggered_bar_ctf", ident, abs(worst["error"]), 0.0, tolerance=tol,
                              tolerance_text=f"≤{tol}", sigma=worst["ctf_std"],
                              sigma_null_means="the bar measurement gave no CTF sigma",
                              note=_bar_note(worst, groups, thr)))  # fmt: skip
    return rows, out


def _bar_note(worst: dict, groups: list[dict], thr: float) -> str:
    beyond = [g for g in groups if g["beyond_single_nyquist"] and g["compared"]]
    text = (
        f"largest error at group {worst['group']} (period {worst['period_single_px']:.2f} px of one array): CTF "
        f"measured {worst['ctf_measured']:.3f}, Coltman {worst['ctf_predicted']:.3f}"
    )
    if beyond:
        ok = [str(g["group"]) for g in beyond if g["resolved_as_predicted"]]
        res = [str(g["group"]) for g in beyond if g["resolved_measured"]]
        text += (
            f"; groups above one array's Nyquist (< 2 px per period): {', '.join(str(g['group']) for g in beyond)}, "
            f"resolved (CTF >= {thr:g}): {', '.join(res) or 'none'}, as predicted: {', '.join(ok) or 'none'}"
        )
    return text
