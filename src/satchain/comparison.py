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
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from satchain import ctf as _ctf
from satchain.prediction import NYQUIST_CY_PER_PX, WEDGE_AXES, Predictions

__all__ = [
    "BAR_COMPARE_MAX_CY_PER_PX",
    "STAR_F_MIN_CY_PER_PX",
    "BarCheck",
    "CheckRow",
    "Comparison",
    "EdgeCheck",
    "NiirsCheck",
    "StarCheck",
    "WedgeCheck",
    "compare",
]

#: Bar groups finer than this (fewer than 2.5 px per period) are listed but not compared with Coltman's CTF.
#: The bar measurement fits the group at its known period with the phase free (measure/_barfit.py), so from
#: 2.5 px per period its CTF no longer depends on where the bars fall on the pixel grid (within 0.03 of
#: Coltman's, up to 0.045 and flagged at integer periods where harmonics alias onto the fitted ones); the
#: sampled max - min used before needed 5 px. The MTF derived from all groups is still plotted.
BAR_COMPARE_MAX_CY_PER_PX = 0.4
#: The star's MTF is compared from this frequency (cy/px) up to Nyquist.
STAR_F_MIN_CY_PER_PX = 0.05


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
    absolute error over 0.05..0.5 cy/px (``directions``); the worst of them; the measured curves."""

    id: str
    directions: dict
    max_abs_error_to_nyquist: float | None
    passed: bool | None
    f_cy_per_px: list
    mtf_measured: dict


@dataclass(frozen=True)
class BarCheck(_Detail):
    """A bar target: measured CTF vs Coltman's (and the paper's Fourier-synthesis CTF) at the groups'
    frequencies (cy/px), compared up to ``compared_up_to_cy_per_px``; the MTF from the measured CTF vs the
    predicted MTF."""

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
    """GIQE 5 NIIRS predicted and measured, with the RER and contrast SNR each comes from."""

    giqe5_predicted: float | None = None
    giqe5_measured: float | None = None
    rer_predicted: float | None = None
    rer_measured: float | None = None
    snr_predicted: float | None = None
    snr_measured: float | None = None
    passed: bool | None = None
    reason: str | None = None


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
        """The checks as a plain-text table (figure, measured, predicted, tolerance, result)."""

        def num(v) -> str:
            return "-" if v is None else f"{v:.4g}"

        width = max([len(r.figure) for r in self.rows] + [15])
        lines = [f"{'figure of merit':{width}}  {'measured':>10}  {'predicted':>10}  {'tolerance':>9}  result"]
        for r in self.rows:
            verdict = "n/a" if r.passed is None else ("pass" if r.passed else "FAIL")
            lines.append(
                f"{r.figure:{width}}  {num(r.measured):>10}  {num(r.predicted):>10}  {r.tolerance_text:>9}  {verdict}"
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


def _finite(v) -> float | None:
    """A finite float, or None (missing, None, NaN or inf)."""
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _within(error: float | None, tolerance: float) -> bool | None:
    return None if error is None else bool(abs(error) <= tolerance)


def _measured_dict(measured: Any) -> dict[str, Any]:
    if isinstance(measured, Mapping):
        return dict(measured)
    if hasattr(measured, "auto"):  # satchain.api.Measurements
        out = dict(measured.auto.to_dict())
        if getattr(measured, "snr", None) is not None:
            out["snr"] = measured.snr.to_dict()
        return out
    return dict(measured.to_dict())


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
        rows.append(
            CheckRow(
                f"edge {e['id']} MTF@Nyquist ({e['direction']})", "edge_mtf_at_nyquist", e["id"], meas,
                p.mtf_at_nyquist, err, tol.edge_mtf_at_nyquist, f"±{tol.edge_mtf_at_nyquist}",
                _within(err, tol.edge_mtf_at_nyquist), why,
            )
        )  # fmt: skip
        why = None if a_err is not None else "no measured or true angle"
        rows.append(
            CheckRow(
                f"edge {e['id']} angle (deg)", "edge_angle", e["id"], a, a_true, a_err, tol.edge_angle_deg,
                f"±{tol.edge_angle_deg}", _within(a_err, tol.edge_angle_deg), why,
            )
        )  # fmt: skip
    return [EdgeCheck.from_dict(d) for d in details], rows


def _star_checks(measured: dict, pred: Predictions, tol: Any) -> tuple[list[StarCheck], list[CheckRow]]:
    details, rows = [], []
    for st in measured.get("siemens_star", []):
        f = np.asarray(st["f_cy_per_px"], float)
        per_dir, errors = {}, []
        for d, curve in st.get("mtf", {}).items():
            meas = np.array([np.nan if v is None else v for v in curve], float)
            mtf_pred = np.asarray(pred.mtf_along[d.upper()](f), float)
            ok = np.isfinite(meas) & (f >= STAR_F_MIN_CY_PER_PX) & (f <= NYQUIST_CY_PER_PX)
            err = float(np.max(np.abs(meas[ok] - mtf_pred[ok]))) if ok.any() else None
            if err is not None:
                errors.append(err)
            per_dir[d] = {"mtf_predicted": mtf_pred.tolist(), "max_abs_error_to_nyquist": err}
        worst = max(errors) if errors else None
        details.append(
            {
                "id": st["id"],
                "directions": per_dir,
                "max_abs_error_to_nyquist": worst,
                "pass": _within(worst, tol.star_mtf),
                "f_cy_per_px": f.tolist(),
                "mtf_measured": st.get("mtf", {}),
            }
        )
        why = None if worst is not None else f"no finite star MTF between {STAR_F_MIN_CY_PER_PX} and 0.5 cy/px"
        rows.append(
            CheckRow(
                f"star {st['id']} max |MTF error| to Nyquist", "star_mtf", st["id"], worst, 0.0, worst,
                tol.star_mtf, f"≤{tol.star_mtf}", _within(worst, tol.star_mtf), why,
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
        ok = np.isfinite(meas) & (f <= BAR_COMPARE_MAX_CY_PER_PX)
        err = float(np.max(np.abs(meas[ok] - col[ok]))) if ok.any() else None
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
                "ctf_std_measured": _floats(b.get("ctf_std"), f.size),
                "ctf_correction": _floats(b.get("ctf_correction"), f.size),
                "flags": [str(x) for x in b.get("flags", [])],
            }
        )
        lim = BAR_COMPARE_MAX_CY_PER_PX
        why = None if err is not None else f"no group with >= {1 / lim:g} px per period (<= {lim} cy/px)"
        rows.append(
            CheckRow(
                f"bars {b['id']} max |CTF error| (Coltman)", "bar_ctf", b["id"], err, 0.0, err, tol.bar_ctf,
                f"≤{tol.bar_ctf}", _within(err, tol.bar_ctf), why,
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


def _niirs_check(edges: list[EdgeCheck], snr: Mapping[str, Any], pred: Predictions, tol: Any):
    from satchain import units
    from satchain.quality import giqe5, giqe5_rer

    r_act, r_alt = _mean_rer(edges, "ACT"), _mean_rer(edges, "ALT")
    snr_m = _finite(snr.get("snr"))
    rer_m = giqe5_rer(r_act, r_alt) if r_act and r_alt else None
    niirs_m, why = None, None
    if rer_m is None:
        why = "needs a measured RER from both an ACT and an ALT edge"
    elif snr_m is None or snr_m <= 0:
        why = "no SNR measured on the image: " + str(snr.get("reason") or "missing")
    else:
        gsd_in = float(units.m_to_inches(pred.gsd_los_m))
        niirs_m = giqe5(gsd_in=gsd_in, rer=rer_m, snr=snr_m, elevation_deg=pred.elevation_deg)
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
    }
    row = CheckRow(
        "NIIRS (GIQE 5)", "niirs", None, niirs_m, pr, err, tol.niirs, f"±{tol.niirs}", _within(err, tol.niirs), why
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
        rows.append(CheckRow(label.format(sk["id"]), kind, sk["id"], None, None, None, t, text.format(t), None, reason))
    return rows


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
    return Comparison(tuple(rows), tuple(edges), tuple(stars), tuple(bars), tuple(wedges), niirs, snr)
