"""Measured vs predicted: the one place where measurement meets prediction, as a pure function.

:func:`compare` takes the measurements (:func:`satchain.measure.auto.measure_auto`'s result, plus the SNR of
:func:`satchain.measure.snr.measure_snr`), the predictions (:func:`satchain.prediction.predict`) and the
tolerances, and returns a :class:`Comparison`: one :class:`CheckRow` per check, and the per-target detail
the report plots. No I/O, no system object. The checks:

* slanted edge -- MTF at Nyquist (0.5 cy/px along the edge normal, the e-SFR's axis): ``|measured -
  predicted| <= edge_mtf_at_nyquist``; and the edge angle: ``|measured - truth| <= edge_angle_deg``;
* Siemens star -- the largest ``|measured - predicted|`` MTF along each sector direction (ACT, ALT,
  diagonals) over 0.05..0.5 cy/px: ``<= star_mtf``;
* bar target -- the largest ``|measured - Coltman|`` CTF along the bars' modulation axis, for groups with
  at least 2.5 px per period (:data:`BAR_COMPARE_MAX_CY_PER_PX`): ``<= bar_ctf``;
* hyperbolic wedge -- resolvable line width: ``|measured / predicted - 1| <= wedge_resolution_rel``, the
  prediction being the same 15 % crossing measured on the wedge's noise-free predicted image;
* NIIRS -- GIQE 5 from the measured edge RERs and image SNR vs the predicted GIQE 5: ``<= niirs``.

Every limit is inclusive. A check whose measurement is missing (the target could not be measured -- it is
in the measurement's ``skipped`` list -- or nothing lies in the compared range) is **n/a** (``passed =
None``, with ``reason``), never a failure.

Every row carries ``sigma``, the 1-sigma of its ``error``, or ``sigma_null_means`` saying why not. The
prediction is exact for the simulated system model, so sigma is the measurement's: the edge's
``mtf_at_nyquist_sigma`` and the angle's from its per-line position noise; the star's MTF 1-sigma at the
direction and frequency of the largest error; the bars' ``ctf_std`` at the group of the largest error; the
NIIRS's RER (bounded from each edge's MTF 1-sigma) and SNR (:data:`SNR_REL_SIGMA`) sigmas through GIQE 5
(the formulas in :mod:`satchain.check_sigma`). ``z = error / sigma``; a row whose tolerance is below
:data:`NOISE_SIGMAS` sigma is ``tolerance_inside_noise`` (it can fail on noise alone). For star and bars
the error is a maximum over many points, so its z is biased high (a maximum of noise).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from satchain import ctf as _ctf
from satchain.check_sigma import SNR_REL_SIGMA, edge_angle_sigma, edge_angle_sigma_deg, niirs_sigma, rer_sigma_bound
from satchain.prediction import NYQUIST_CY_PER_PX, WEDGE_AXES, Predictions

__all__ = [
    "BAR_COMPARE_MAX_CY_PER_PX",
    "NOISE_SIGMAS",
    "SNR_REL_SIGMA",
    "STAR_F_MIN_CY_PER_PX",
    "BarCheck",
    "CheckRow",
    "Comparison",
    "EdgeCheck",
    "NiirsCheck",
    "StarCheck",
    "WedgeCheck",
    "compare",
    "edge_angle_sigma_deg",
    "row_texts",
    "signed_text",
]

#: Bar groups finer than this (fewer than 2.5 px per period) are listed but not compared with Coltman's CTF.
#: The bar measurement fits the group at its known period with the phase free (measure/_barfit.py), so from
#: 2.5 px per period its CTF no longer depends on where the bars fall on the pixel grid (within 0.03 of
#: Coltman's, up to 0.045 and flagged at integer periods where harmonics alias onto the fitted ones); the
#: sampled max - min used before needed 5 px. The MTF derived from all groups is still plotted.
BAR_COMPARE_MAX_CY_PER_PX = 0.4
#: The star's MTF is compared from this frequency (cy/px) up to Nyquist.
STAR_F_MIN_CY_PER_PX = 0.05
#: A tolerance narrower than this many sigma of its error is "inside the noise": the check can fail on noise.
NOISE_SIGMAS = 2.0
#: Why a prediction carries no sigma: it is computed from the very system model the image was simulated with.
PREDICTION_SIGMA_NOTE = "the prediction is exact for the simulated system model (its sigma is 0)"


@dataclass(frozen=True)
class CheckRow:
    """One pass/fail check.

    ``measured`` / ``predicted`` are in the check's unit (MTF and CTF: unitless; wedge: ground m; NIIRS: levels;
    for star and bars ``measured`` is the largest absolute error and ``predicted`` 0). ``error`` is what the
    tolerance limits (absolute, or relative for the wedge). ``passed`` is None (n/a) when the measurement is
    missing; ``reason`` then says why. ``sigma`` is the 1-sigma uncertainty of ``error`` (from the measurement's
    uncertainty and the prediction's), in the unit of ``error``; when it is None, ``sigma_null_means`` says why.
    """

    figure: str
    kind: str
    id: str | None
    measured: float | None
    predicted: float | None
    error: float | None
    tolerance: float
    tolerance_text: str
    passed: bool | None
    reason: str | None = None
    sigma: float | None = None
    sigma_null_means: str | None = None

    @property
    def z(self) -> float | None:
        """``error / sigma`` (None without both, or with a zero sigma)."""
        if self.error is None or self.sigma is None or not self.sigma > 0:
            return None
        return self.error / self.sigma

    @property
    def tolerance_inside_noise(self) -> bool | None:
        """True when the tolerance is narrower than 2 sigma: the check can fail on noise alone (None: no sigma)."""
        if self.sigma is None:
            return None
        return bool(self.tolerance < NOISE_SIGMAS * self.sigma)

    def to_dict(self) -> dict[str, Any]:
        return {
            "figure": self.figure,
            "kind": self.kind,
            "id": self.id,
            "measured": self.measured,
            "predicted": self.predicted,
            "error": self.error,
            "tolerance": self.tolerance_text,
            "tolerance_value": self.tolerance,
            "pass": self.passed,
            "reason": self.reason,
            "sigma": self.sigma,
            "sigma_null_means": self.sigma_null_means,
            "z": self.z,
            "tolerance_inside_noise": self.tolerance_inside_noise,
        }


class _Detail:
    """Per-target detail: ``to_dict()`` gives the results.json entry (``passed`` is written ``pass``)."""

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]):
        return cls(**{("passed" if k == "pass" else k): v for k, v in d.items()})

    def to_dict(self) -> dict[str, Any]:
        return {("pass" if f.name == "passed" else f.name): getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class EdgeCheck(_Detail):
    """A slanted edge: the measured and predicted MTF along its ``normal`` (x = ACT, y = ALT) at the measured
    frequencies ``f_cy_per_px``, the MTF at Nyquist (0.5 cy/px) both ways and its error, the angle (deg)
    measured and true, the measured RER and MTF50 (cy/px); the measurement's 1-sigma noise (at Nyquist and per
    frequency) and its quality flags."""

    id: str
    direction: str
    normal: list
    angle_deg: float | None
    angle_deg_truth: float | None
    mtf_at_nyquist_measured: float | None
    mtf_at_nyquist_predicted: float
    mtf_at_nyquist_error: float | None
    passed: bool | None
    rer_measured: float | None
    mtf50_cy_per_px: float | None
    f_cy_per_px: list
    mtf_measured: list
    mtf_predicted: list
    mtf_at_nyquist_sigma: float | None = None
    mtf_sigma: list | None = None
    flags: list | None = None


@dataclass(frozen=True)
class StarCheck(_Detail):
    """A Siemens star: per direction (ACT, ALT, D45, D135) the predicted MTF at ``f_cy_per_px`` and the largest
    absolute error over 0.05..0.5 cy/px (``directions``, each with the frequency where it occurs and the
    measurement's 1-sigma there); the worst of them (``max_abs_error_sigma``: the measured MTF's 1-sigma at
    that direction and frequency, from measure_star's per-annulus fit residuals and input modulation); the
    measured curves and their 1-sigma; the measurement's quality flags."""

    id: str
    directions: dict
    max_abs_error_to_nyquist: float | None
    passed: bool | None
    f_cy_per_px: list
    mtf_measured: dict
    max_abs_error_sigma: float | None = None
    worst_direction: str | None = None
    worst_f_cy_per_px: float | None = None
    mtf_std_measured: dict = field(default_factory=dict)
    flags: list = field(default_factory=list)


@dataclass(frozen=True)
class BarCheck(_Detail):
    """A bar target: measured CTF vs Coltman's (and the paper's Fourier-synthesis CTF) at the groups'
    frequencies (cy/px), compared up to ``compared_up_to_cy_per_px``; the MTF from the measured CTF vs the
    predicted MTF. ``ctf_measured`` is the square-wave CTF the measurement reports: the group's fitted
    modulation (``ctf_raw_measured``) plus ``ctf_correction``, the difference between the model's Coltman CTF
    and the same estimator on the group rendered through the target's joint MTF model (finite 3-bar group,
    aliased harmonics, grid phase; see measure/_barjoint.py). ``max_abs_error_sigma`` is ``ctf_std_measured``
    at the group with the largest error (``worst_f_cy_per_px``)."""

    id: str
    compared_up_to_cy_per_px: float
    direction: str | None
    f_cy_per_px: list
    ctf_measured: list
    ctf_coltman_predicted: list
    ctf_fourier_synthesis_predicted: list
    mtf_from_ctf_measured: list
    mtf_predicted: list
    max_abs_error: float | None
    passed: bool | None
    ctf_std_measured: list = field(default_factory=list)
    ctf_correction: list = field(default_factory=list)
    flags: list = field(default_factory=list)
    ctf_raw_measured: list = field(default_factory=list)
    max_abs_error_sigma: float | None = None
    worst_f_cy_per_px: float | None = None


@dataclass(frozen=True)
class WedgeCheck(_Detail):
    """A hyperbolic wedge: resolvable line width (ground m) measured and predicted across the stripes along
    ``axis``, the GSD (m), their ratios, and the contrast scan (``position_m`` along the wedge from its wide end,
    ``line_width_m``) measured (``contrast``) and predicted (``contrast_predicted``: the same scan on the wedge's
    noise-free predicted image, :mod:`satchain.wedge_prediction`). 1-sigma: ``resolution_m_std`` (the measured
    crossing's, from the image noise: the predicted image re-measured with the sensor's noise added; the
    measurement's own, larger, slope-based estimate is ``resolution_m_std_measure``), ``relative_error_sigma``
    (of ``relative_error``: ``resolution_m_std / resolution_predicted_m``) and, reported beside them,
    ``resolution_predicted_m_std``: the prediction's spread over sub-pixel placements of the pixel grid
    (``resolution_predicted_by_placement_m``), the uncertainty of a prediction for a wedge whose placement is
    unknown (a run's placement is known, so it is not part of the sigma)."""

    id: str
    orientation: str
    axis: str
    resolution_m: float | None
    resolution_predicted_m: float | None
    gsd_m: float | None
    resolution_over_gsd: float | None
    relative_error: float | None
    passed: bool | None
    threshold: float | None
    position_m: list | None
    contrast: list | None
    contrast_predicted: list | None = None
    line_width_m: list | None = None
    resolution_m_std: float | None = None
    resolution_m_std_measure: float | None = None
    resolution_predicted_m_std: float | None = None
    resolution_predicted_by_placement_m: list | None = None
    relative_error_sigma: float | None = None


@dataclass(frozen=True)
class NiirsCheck(_Detail):
    """GIQE 5 NIIRS predicted and measured, with the RER and contrast SNR each comes from;
    ``giqe5_measured_sigma``: the measured NIIRS's 1-sigma (RER and SNR sigmas through GIQE 5)."""

    giqe5_predicted: float | None = None
    giqe5_measured: float | None = None
    rer_predicted: float | None = None
    rer_measured: float | None = None
    snr_predicted: float | None = None
    snr_measured: float | None = None
    passed: bool | None = None
    reason: str | None = None
    giqe5_measured_sigma: float | None = None


@dataclass(frozen=True)
class Comparison:
    """The result of :func:`compare`: the checks and, per target kind, the detail the report plots."""

    rows: tuple[CheckRow, ...]
    slanted_edges: tuple[EdgeCheck, ...] = ()
    siemens_star: tuple[StarCheck, ...] = ()
    bar_targets: tuple[BarCheck, ...] = ()
    hyperbolic_wedge: tuple[WedgeCheck, ...] = ()
    niirs: NiirsCheck = field(default_factory=NiirsCheck)
    snr_measurement: dict = field(default_factory=dict)

    @property
    def n_checked(self) -> int:
        return sum(r.passed is not None for r in self.rows)

    @property
    def n_failed(self) -> int:
        return sum(r.passed is False for r in self.rows)

    @property
    def passed(self) -> bool | None:
        """False when any check failed; None when no check could be evaluated; True otherwise."""
        if self.n_failed:
            return False
        return True if self.n_checked else None

    def __str__(self) -> str:
        """The checks as a plain-text table (figure, measured, predicted, error, sigma, z, tolerance, result)."""
        width = max([len(r.figure) for r in self.rows] + [15])
        head = ("measured", "predicted", "error", "sigma", "z", "tolerance")
        lines = [f"{'figure of merit':{width}}  " + "  ".join(f"{h:>10}" for h in head) + "  result"]
        for r in self.rows:
            cells = row_texts(r)
            lines.append(
                f"{r.figure:{width}}  " + "  ".join(f"{cells[h]:>10}" for h in head) + f"  {cells['result']}"
            )
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {
            "slanted_edges": [d.to_dict() for d in self.slanted_edges],
            "siemens_star": [d.to_dict() for d in self.siemens_star],
            "bar_targets": [d.to_dict() for d in self.bar_targets],
            "hyperbolic_wedge": [d.to_dict() for d in self.hyperbolic_wedge],
            "niirs": self.niirs.to_dict(),
            "snr_measurement": self.snr_measurement,
            "summary": [r.to_dict() for r in self.rows],
        }


def signed_text(v: float | None, digits: int = 3) -> str:
    """``v`` with its sign and ``digits`` significant digits ("-0.00388", never "+0.00"); "-" when missing."""
    return "-" if v is None else f"{v:+.{digits}g}"


def row_texts(r: CheckRow) -> dict[str, str]:
    """A row's cells as text for the terminal: numbers to 4 significant digits, the error and z signed, and
    the result with "tolerance inside noise" when the tolerance is below :data:`NOISE_SIGMAS` sigma."""

    def num(v) -> str:
        return "-" if v is None else f"{v:.4g}"

    verdict = "n/a" if r.passed is None else ("pass" if r.passed else "FAIL")
    if r.tolerance_inside_noise:
        verdict += " (tolerance inside noise)"
    return {
        "measured": num(r.measured),
        "predicted": num(r.predicted),
        "error": signed_text(r.error),
        "sigma": "-" if r.sigma is None else f"{r.sigma:.2g}",
        "z": "-" if r.z is None else f"{r.z:+.2f}",
        "tolerance": r.tolerance_text,
        "result": verdict,
    }


def _finite(v) -> float | None:
    """A finite float, or None (missing, None, NaN or inf)."""
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _within(error: float | None, tolerance: float) -> bool | None:
    return None if error is None else bool(abs(error) <= tolerance)


def _sigma_or_why(sigma: float | None, error: float | None, why: str) -> tuple[float | None, str | None]:
    """``(sigma, None)``, or ``(None, reason)`` when there is no error to qualify or no finite sigma. The
    prediction adds nothing: it is exact for the simulated model (:data:`PREDICTION_SIGMA_NOTE`)."""
    if error is None:
        return None, "no error (the check is n/a)"
    sigma = _finite(sigma)
    if sigma is None or sigma < 0:
        return None, why
    return sigma, None


def _measured_dict(measured: Any) -> dict[str, Any]:
    if isinstance(measured, Mapping):
        return dict(measured)
    if hasattr(measured, "auto"):  # satchain.api.Measurements
        out = _with_edge_cnr(measured.auto)
        if getattr(measured, "snr", None) is not None:
            out["snr"] = measured.snr.to_dict()
        return out
    return _with_edge_cnr(measured)


def _with_edge_cnr(auto: Any) -> dict[str, Any]:
    """``auto.to_dict()`` with each edge's contrast-to-noise ratio (from its EdgeResult) for the angle's sigma."""
    out = dict(auto.to_dict())
    cnr = {}
    for it in getattr(auto, "items", ()):
        r = getattr(it, "result", None)
        c, n = getattr(r, "contrast", None), getattr(r, "noise_sigma", None)
        if it.kind == "slanted_edge" and c is not None and n:
            cnr[it.id] = abs(float(c)) / float(n)
    out["slanted_edges"] = [dict(e, cnr=e.get("cnr", cnr.get(e.get("id")))) for e in out.get("slanted_edges", [])]
    return out


def _edge_checks(measured: dict, pred: Predictions, tol: Any) -> tuple[list[EdgeCheck], list[CheckRow]]:
    details, rows = [], []
    for e in measured.get("slanted_edges", []):
        p = pred.edge(e["id"], e["direction"])
        meas = _finite(e.get("mtf_at_nyquist"))
        err = None if meas is None else meas - p.mtf_at_nyquist
        f = np.asarray(e.get("f_cy_per_px", []), float)
        a, a_true = _finite(e.get("angle_deg")), _finite(e.get("angle_deg_truth"))
        a_err = None if a is None or a_true is None else a - a_true
        details.append(
            {
                "id": e["id"],
                "direction": e["direction"],
                "normal": list(p.normal),
                "angle_deg": a,
                "angle_deg_truth": a_true,
                "mtf_at_nyquist_measured": meas,
                "mtf_at_nyquist_predicted": p.mtf_at_nyquist,
                "mtf_at_nyquist_error": err,
                "pass": _within(err, tol.edge_mtf_at_nyquist),
                "rer_measured": _finite(e.get("rer")),
                "mtf50_cy_per_px": _finite(e.get("mtf50_cy_per_px")),
                "f_cy_per_px": f.tolist(),
                "mtf_measured": e.get("mtf", []),
                "mtf_predicted": p.mtf(f).tolist(),
                "mtf_at_nyquist_sigma": _finite(e.get("mtf_at_nyquist_sigma", e.get("mtf_at_nyquist_std"))),
                "mtf_sigma": e.get("mtf_sigma"),
                "flags": list(e.get("flags") or []),
            }
        )
        why = None if meas is not None else "the edge gave no MTF at Nyquist"
        sig = _sigma_or_why(details[-1]["mtf_at_nyquist_sigma"], err, "the edge measurement gave no MTF sigma")
        rows.append(
            CheckRow(
                f"edge {e['id']} MTF@Nyquist ({e['direction']})", "edge_mtf_at_nyquist", e["id"], meas,
                p.mtf_at_nyquist, err, tol.edge_mtf_at_nyquist, f"±{tol.edge_mtf_at_nyquist}",
                _within(err, tol.edge_mtf_at_nyquist), why, *sig,
            )
        )  # fmt: skip
        why = None if a_err is not None else "no measured or true angle"
        sig = _sigma_or_why(edge_angle_sigma(e), a_err, "no contrast-to-noise, line count or region for the edge")
        rows.append(
            CheckRow(
                f"edge {e['id']} angle (deg)", "edge_angle", e["id"], a, a_true, a_err, tol.edge_angle_deg,
                f"±{tol.edge_angle_deg}", _within(a_err, tol.edge_angle_deg), why, *sig,
            )
        )  # fmt: skip
    return [EdgeCheck.from_dict(d) for d in details], rows


def _star_direction(f: np.ndarray, curve, std, mtf_pred: np.ndarray) -> dict[str, Any]:
    """One direction of a star: the largest |error| over STAR_F_MIN..Nyquist, where, and its 1-sigma."""
    meas = np.array([np.nan if v is None else v for v in curve], float)
    sd = np.array(_floats(std, f.size), float)
    ok = np.isfinite(meas) & (f >= STAR_F_MIN_CY_PER_PX) & (f <= NYQUIST_CY_PER_PX)
    out: dict[str, Any] = {"mtf_predicted": mtf_pred.tolist(), "max_abs_error_to_nyquist": None}
    if ok.any():
        i = np.flatnonzero(ok)[np.argmax(np.abs(meas[ok] - mtf_pred[ok]))]
        out.update(
            max_abs_error_to_nyquist=float(abs(meas[i] - mtf_pred[i])),
            worst_f_cy_per_px=float(f[i]),
            max_abs_error_sigma=_finite(sd[i]),
        )
    return out


def _star_checks(measured: dict, pred: Predictions, tol: Any) -> tuple[list[StarCheck], list[CheckRow]]:
    details, rows = [], []
    for st in measured.get("siemens_star", []):
        f = np.asarray(st["f_cy_per_px"], float)
        stds = st.get("mtf_std") or {}
        per_dir = {
            d: _star_direction(f, curve, stds.get(d), np.asarray(pred.mtf_along[d.upper()](f), float))
            for d, curve in st.get("mtf", {}).items()
        }
        done = {d: v for d, v in per_dir.items() if v["max_abs_error_to_nyquist"] is not None}
        wd = max(done, key=lambda d: done[d]["max_abs_error_to_nyquist"]) if done else None
        worst = None if wd is None else done[wd]["max_abs_error_to_nyquist"]
        w_sig = None if wd is None else done[wd]["max_abs_error_sigma"]
        details.append(
            {
                "id": st["id"],
                "directions": per_dir,
                "max_abs_error_to_nyquist": worst,
                "pass": _within(worst, tol.star_mtf),
                "f_cy_per_px": f.tolist(),
                "mtf_measured": st.get("mtf", {}),
                "max_abs_error_sigma": w_sig,
                "worst_direction": wd,
                "worst_f_cy_per_px": None if wd is None else done[wd]["worst_f_cy_per_px"],
                "mtf_std_measured": {d: _floats(v, f.size) for d, v in stds.items()},
                "flags": [str(x) for x in st.get("flags", [])],
            }
        )
        why = None if worst is not None else f"no finite star MTF between {STAR_F_MIN_CY_PER_PX} and 0.5 cy/px"
        sig = _sigma_or_why(w_sig, worst, "the star measurement gave no MTF sigma at the worst frequency")
        rows.append(
            CheckRow(
                f"star {st['id']} max |MTF error| to Nyquist", "star_mtf", st["id"], worst, 0.0, worst,
                tol.star_mtf, f"≤{tol.star_mtf}", _within(worst, tol.star_mtf), why, *sig,
            )
        )  # fmt: skip
    return [StarCheck.from_dict(d) for d in details], rows


def _floats(values, n: int) -> list:
    """A per-group list as floats (NaN where absent)."""
    if values is None:
        return [np.nan] * n
    return [np.nan if v is None else float(v) for v in values]


def _bar_checks(measured: dict, pred: Predictions, tol: Any) -> tuple[list[BarCheck], list[CheckRow]]:
    details, rows = [], []
    for b in measured.get("bar_targets", []):
        m = pred.mtf_along["ALT" if str(b.get("direction", "ACT")).upper() == "ALT" else "ACT"]
        f = np.asarray(b["f_cy_per_px"], float)
        meas = np.array([np.nan if v is None else v for v in b["ctf"]], float)
        col = np.asarray(_ctf.coltman_ctf(f, m), float)
        std = np.array(_floats(b.get("ctf_std"), f.size), float)
        corr = np.array(_floats(b.get("ctf_correction"), f.size), float)
        ok = np.isfinite(meas) & (f <= BAR_COMPARE_MAX_CY_PER_PX)
        err, i = None, None
        if ok.any():
            i = int(np.flatnonzero(ok)[np.argmax(np.abs(meas[ok] - col[ok]))])
            err = float(abs(meas[i] - col[i]))
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
                "pass": _within(err, tol.bar_ctf),
                "ctf_std_measured": std.tolist(),
                "ctf_correction": corr.tolist(),
                "flags": [str(x) for x in b.get("flags", [])],
                "ctf_raw_measured": np.where(np.isfinite(corr), meas - corr, meas).tolist(),
                "max_abs_error_sigma": None if i is None else _finite(std[i]),
                "worst_f_cy_per_px": None if i is None else float(f[i]),
            }
        )
        lim = BAR_COMPARE_MAX_CY_PER_PX
        why = None if err is not None else f"no group with >= {1 / lim:g} px per period (<= {lim} cy/px)"
        sig = _sigma_or_why(details[-1]["max_abs_error_sigma"], err, "the bar measurement gave no CTF sigma")
        rows.append(
            CheckRow(
                f"bars {b['id']} max |CTF error| (Coltman)", "bar_ctf", b["id"], err, 0.0, err, tol.bar_ctf,
                f"≤{tol.bar_ctf}", _within(err, tol.bar_ctf), why, *sig,
            )
        )  # fmt: skip
    return [BarCheck.from_dict(d) for d in details], rows


def _wedge_sigma(res, pr, p, sd_measure) -> tuple[float | None, float | None, str | None]:
    """(1-sigma of the measured crossing in m, 1-sigma of ``res / pr - 1``, why None).

    The crossing's 1-sigma from noise is the prediction's parametric bootstrap (the predicted image re-measured
    with the sensor's noise added), else the measurement's own estimate. The prediction is made at the image's
    own placement on the pixel grid, which the run knows exactly, so the spread over placements is reported
    beside it (``resolution_predicted_m_std``) and not added."""
    sd = None if p is None else _finite(p.resolution_noise_m_std)
    sd = sd_measure if sd is None else sd
    if res is None or pr is None:
        return sd, None, "no relative error (a resolution is missing)"
    if sd is None:
        return None, None, "no noise model (no sensor) and no uncertainty from the measurement"
    return sd, sd / pr, None


def _wedge_checks(measured: dict, pred: Predictions, tol: Any) -> tuple[list[WedgeCheck], list[CheckRow]]:
    details, rows = [], []
    for w in measured.get("hyperbolic_wedge", []):
        axis = WEDGE_AXES[w["orientation"]]
        p = pred.wedges.get(str(w["id"]))
        res, pr = _finite(w.get("resolution_m")), None if p is None else _finite(p.resolution_m)
        sd_measure, sd_pred = _finite(w.get("resolution_m_std")), None if p is None else _finite(p.resolution_m_std)
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
                "pass": _within(rel, tol.wedge_resolution_rel),
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
                tol.wedge_resolution_rel, f"±{tol.wedge_resolution_rel:.0%}", _within(rel, tol.wedge_resolution_rel),
                why, sigma, sigma_why,
            )
        )  # fmt: skip
    return [WedgeCheck.from_dict(d) for d in details], rows


def _mean_rer(edges: list[EdgeCheck], direction: str) -> float | None:
    v = [e.rer_measured for e in edges if e.direction == direction and e.rer_measured is not None]
    return float(np.mean(v)) if v else None


def _mean_rer_sigma(edges: list[EdgeCheck], direction: str) -> float | None:
    """1-sigma of the mean RER of the edges along ``direction`` (independent noise per edge)."""
    sig = [rer_sigma_bound(e.f_cy_per_px, e.mtf_sigma) for e in edges if e.direction == direction and e.rer_measured]
    if not sig or any(v is None for v in sig):
        return None
    return float(np.sqrt(np.sum(np.square(sig))) / len(sig))


def _niirs_sigma(r_act: float, r_alt: float, snr_m: float, edges: list[EdgeCheck], gsd_in: float,
                 elevation_deg: float) -> tuple[float | None, str | None]:  # fmt: skip
    s_act, s_alt = _mean_rer_sigma(edges, "ACT"), _mean_rer_sigma(edges, "ALT")
    if s_act is None or s_alt is None:
        return None, "an edge gave no MTF sigma, so the RER has none"
    sig = niirs_sigma(r_act, r_alt, snr_m, rer_act_sigma=s_act, rer_alt_sigma=s_alt, gsd_in=gsd_in,
                      elevation_deg=elevation_deg)  # fmt: skip
    return sig, None


def _niirs_check(edges: list[EdgeCheck], snr: Mapping[str, Any], pred: Predictions, tol: Any):
    from satchain import units
    from satchain.quality import giqe5, giqe5_rer

    r_act, r_alt = _mean_rer(edges, "ACT"), _mean_rer(edges, "ALT")
    snr_m = _finite(snr.get("snr"))
    rer_m = giqe5_rer(r_act, r_alt) if r_act and r_alt else None
    niirs_m, why, sig = None, None, (None, "no error (the check is n/a)")
    if rer_m is None:
        why = "needs a measured RER from both an ACT and an ALT edge"
    elif snr_m is None or snr_m <= 0:
        why = "no SNR measured on the image: " + str(snr.get("reason") or "missing")
    else:
        gsd_in = float(units.m_to_inches(pred.gsd_los_m))
        niirs_m = giqe5(gsd_in=gsd_in, rer=rer_m, snr=snr_m, elevation_deg=pred.elevation_deg)
        sig = _niirs_sigma(r_act, r_alt, snr_m, edges, gsd_in, pred.elevation_deg)
    pr = _finite(pred.giqe5)
    err = None if niirs_m is None or pr is None else niirs_m - pr
    detail = {
        "giqe5_predicted": pr,
        "giqe5_measured": niirs_m,
        "rer_predicted": _finite(pred.rer),
        "rer_measured": rer_m,
        "snr_predicted": _finite(pred.snr),
        "snr_measured": snr_m,
        "pass": _within(err, tol.niirs),
        "reason": why,
        "giqe5_measured_sigma": sig[0] if err is not None else None,
    }
    sig = sig if err is not None else (None, "no error (the check is n/a)")
    row = CheckRow(
        "NIIRS (GIQE 5)", "niirs", None, niirs_m, pr, err, tol.niirs, f"±{tol.niirs}", _within(err, tol.niirs), why,
        *sig,
    )
    return NiirsCheck.from_dict(detail), row


#: The check a target of each scene kind would have had: (figure label, row kind, tolerance attribute, text).
_SKIPPED_CHECKS = {
    "slanted_edge": ("edge {} MTF@Nyquist", "edge_mtf_at_nyquist", "edge_mtf_at_nyquist", "±{}"),
    "siemens_star": ("star {} max |MTF error| to Nyquist", "star_mtf", "star_mtf", "≤{}"),
    "bar_target": ("bars {} max |CTF error| (Coltman)", "bar_ctf", "bar_ctf", "≤{}"),
    "hyperbolic_wedge": ("wedge {} resolution (m)", "wedge_resolution", "wedge_resolution_rel", "±{:.0%}"),
}


def _skipped_rows(measured: dict, tol: Any) -> list[CheckRow]:
    """An n/a row for every target the measurement had to skip (real-world objects have no check)."""
    rows = []
    for sk in measured.get("skipped", []):
        if sk.get("kind") not in _SKIPPED_CHECKS:
            continue
        label, kind, attr, text = _SKIPPED_CHECKS[sk["kind"]]
        t = getattr(tol, attr)
        reason = f"not measured: {sk.get('reason', 'no reason given')}"
        rows.append(
            CheckRow(label.format(sk["id"]), kind, sk["id"], None, None, None, t, text.format(t), None, reason, None,
                     "no error (the target was not measured)")
        )  # fmt: skip
    return rows


def _with_sigma_reason(row: CheckRow) -> CheckRow:
    """Every row carries a sigma or says why not: a row left without either gets a generic reason."""
    if row.sigma is not None or row.sigma_null_means:
        return row
    why = "no error (the check is n/a)" if row.error is None else f"no uncertainty model for {row.kind} checks yet"
    return replace(row, sigma_null_means=why)


def compare(measured: Any, predicted: Predictions, tolerances: Any) -> Comparison:
    """Put measurements beside predictions and check each against its tolerance (pure; no I/O).

    Parameters
    ----------
    measured : AutoResult, Measurements or dict
        ``measure_auto(...)`` or its ``to_dict()`` (``slanted_edges``, ``siemens_star``, ``bar_targets``,
        ``hyperbolic_wedge``, ``skipped``: each skipped target gets an n/a row); an optional ``"snr"``
        entry (``measure_snr(...).to_dict()``) feeds the NIIRS check.
    predicted : Predictions
        From :func:`satchain.prediction.predict` (or :func:`~satchain.prediction.predict_from_mtf`).
    tolerances : Tolerances
        Any object with ``edge_mtf_at_nyquist``, ``edge_angle_deg``, ``star_mtf``, ``bar_ctf``,
        ``wedge_resolution_rel`` and ``niirs`` (see :class:`satchain.runconfig.Tolerances`).

    Returns
    -------
    Comparison
        ``rows`` (one :class:`CheckRow` per check), ``passed`` (False if any failed, None if none could be
        evaluated) and the per-target detail.
    """
    m = _measured_dict(measured)
    edges, rows = _edge_checks(m, predicted, tolerances)
    stars, r = _star_checks(m, predicted, tolerances)
    rows += r
    bars, r = _bar_checks(m, predicted, tolerances)
    rows += r
    wedges, r = _wedge_checks(m, predicted, tolerances)
    rows += r
    snr = dict(m.get("snr") or {})
    rows += _skipped_rows(m, tolerances)
    niirs, row = _niirs_check(edges, snr, predicted, tolerances)
    rows.append(row)
    rows = [_with_sigma_reason(r) for r in rows]
    return Comparison(tuple(rows), tuple(edges), tuple(stars), tuple(bars), tuple(wedges), niirs, snr)
