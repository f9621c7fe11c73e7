"""The comparison's records: one :class:`CheckRow` per check, the per-target detail the report plots
(:class:`EdgeCheck`, :class:`StarCheck`, :class:`BarCheck`, :class:`WedgeCheck`, :class:`NiirsCheck`) and their
container :class:`Comparison`, with the texts the terminal table prints."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import Field, dataclass, field, fields
from typing import Any, ClassVar

from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge


def result_key(kind: str) -> str:
    """The results.json key of a target kind: the measurement registry's (:data:`satchain.measure.auto.MEASURERS`)."""
    from satchain.measure.auto import MEASURERS

    return MEASURERS[kind].key


__all__ = [
    "NOISE_SIGMAS",
    "REAL_DIFFERENCE_Z",
    "BarCheck",
    "CheckRow",
    "Comparison",
    "EdgeCheck",
    "NiirsCheck",
    "StarCheck",
    "WedgeCheck",
    "row_texts",
    "signed_text",
]

#: A tolerance narrower than this many sigma of its error is "inside the noise": the check can fail on noise alone
#: (issue 29: the tolerance smaller than the measurement's sigma; was 2).
NOISE_SIGMAS = 1.0
#: A row whose ``|z|`` reaches this shows a real difference: it is never marked "inside the noise", whatever its sigma.
REAL_DIFFERENCE_Z = 3.0


@dataclass(frozen=True)
class CheckRow:
    """One pass/fail check.

    ``measured`` / ``predicted`` are in the check's unit (MTF and CTF: unitless; wedge: ground m; NIIRS: levels;
    for the star the MTF measured and predicted where their difference is largest; for bars ``measured`` is the
    largest absolute error and ``predicted`` 0). ``error`` is what the tolerance limits (absolute, or relative
    for the wedge). ``passed`` is None (n/a) when the measurement is missing; ``reason`` then says why.
    ``sigma`` is the 1-sigma uncertainty of ``error`` (from the measurement's uncertainty and the prediction's),
    in the unit of ``error``; when it is None, ``sigma_null_means`` says why. ``model_prediction``: where the
    prediction is the measurement made on a noise-free predicted image (star), the system model's own value
    beside it (their difference is the estimator's systematic); ``note`` says what the row compares, in words.
    ``as_built`` (a run whose camera was simulated as built): the same check against the as-built camera's
    prediction, ``{"predicted", "error", "sigma", "z", "pass"}``, written ``predicted_as_built``, ... (see
    :func:`satchain.comparison.as_built.with_as_built`).
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
    model_prediction: float | None = None
    note: str | None = None
    as_built: dict[str, Any] | None = None

    @property
    def z(self) -> float | None:
        """``error / sigma`` (None without both, or with a zero sigma)."""
        if self.error is None or self.sigma is None or not self.sigma > 0:
            return None
        return self.error / self.sigma

    @property
    def tolerance_inside_noise(self) -> bool | None:
        """True when the tolerance is smaller than the measurement's sigma (:data:`NOISE_SIGMAS`) and ``|z|`` is
        below :data:`REAL_DIFFERENCE_Z`: the check can pass or fail on noise alone. A row whose ``|z|`` shows a
        real difference is never marked, whatever its sigma (None: no sigma)."""
        if self.sigma is None:
            return None
        z = self.z
        return bool(self.tolerance < NOISE_SIGMAS * self.sigma and (z is None or abs(z) < REAL_DIFFERENCE_Z))

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
            "model_prediction": self.model_prediction,
            "note": self.note,
            **({} if self.as_built is None else {f"{k}_as_built": v for k, v in self.as_built.items()}),
        }


class _Detail:
    """Per-target detail: ``to_dict()`` gives the results.json entry (``passed`` is written ``pass``). Each has an
    ``as_built`` entry, written only for a run simulated as built: its predicted quantities (and errors, pass) for
    the camera as built (:func:`satchain.comparison.as_built.with_as_built`)."""

    __dataclass_fields__: ClassVar[dict[str, Field[Any]]]  # (type only) every subclass is a dataclass

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]):
        return cls(**{("passed" if k == "pass" else k): v for k, v in d.items()})

    def to_dict(self) -> dict[str, Any]:
        d = {("pass" if f.name == "passed" else f.name): getattr(self, f.name) for f in fields(self)}
        if d.get("as_built", 0) is None:  # written only for a run simulated as built
            del d["as_built"]
        return d


@dataclass(frozen=True)
class EdgeCheck(_Detail):
    """A slanted edge: the measured and predicted MTF along its ``normal`` (x = ACT, y = ALT) at the measured
    frequencies ``f_cy_per_px``, the MTF at Nyquist (0.5 cy/px) both ways and its error, the angle (deg)
    measured and true, the measured RER and MTF50 (cy/px); the measurement's 1-sigma noise (at Nyquist and per
    frequency) and its quality flags; ``angle_deg_expected``: the true angle through the image geometry (a sheared
    or scaled pushbroom image), which the angle is checked against when given."""

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
    angle_deg_expected: float | None = None  # the truth through the image geometry (written only when given)
    # a pushbroom edge whose lines the line of sight displaces: the MTF at Nyquist as imaged (the displacements
    # folded in, ISO 12233) measured and predicted over its rows, and the motion the measurement removed
    mtf_as_imaged_at_nyquist_measured: float | None = None
    mtf_as_imaged_at_nyquist_predicted: float | None = None
    los_motion_rms_px: float | None = None
    # which MTF at Nyquist the headline is compared as ("aligned": each line located, the per-row terms over its rows;
    # "as_imaged": the lines' displacements about the measurement's edge polynomial folded in, predicted over its
    # rows), both predictions, the polynomial's degree and the rms displacement the geometry predicts over them
    mtf_at_nyquist_compared: str | None = None
    mtf_at_nyquist_predicted_per_row: float | None = None
    mtf_at_nyquist_predicted_as_located: float | None = None
    los_motion_rms_px_predicted: float | None = None
    fit_degree: int | None = None
    # near zero (within 3 sigma: Q >= 2): the model's MTF at Nyquist, and the Rice mean of it and the measurement's
    # noise, which mtf_at_nyquist_predicted then holds (a measured magnitude never reads below its noise)
    mtf_at_nyquist_model: float | None = None
    mtf_at_nyquist_noise_floor: float | None = None
    as_built: dict | None = None  # the prediction for the camera as built (written only for such a run)

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        for k in ("angle_deg_expected", "mtf_as_imaged_at_nyquist_measured", "mtf_as_imaged_at_nyquist_predicted",
                  "los_motion_rms_px", "mtf_at_nyquist_compared", "mtf_at_nyquist_predicted_per_row",
                  "mtf_at_nyquist_predicted_as_located", "los_motion_rms_px_predicted", "fit_degree",
                  "mtf_at_nyquist_model", "mtf_at_nyquist_noise_floor"):  # fmt: skip
            if d[k] is None:
                del d[k]
        return d


@dataclass(frozen=True)
class StarCheck(_Detail):
    """A Siemens star: per direction (ACT, ALT, D45, D135, in ``directions``) the predicted MTF at ``f_cy_per_px``
    (``mtf_predicted``: the star measured on its noise-free predicted image, :mod:`satchain.prediction.star`;
    the system MTF when there is no such prediction) and the system MTF (``mtf_model``), the largest absolute
    error over 0.05..0.5 cy/px with its sign, frequency and the measurement's 1-sigma there, and the
    estimator's systematic (``mtf_predicted - mtf_model``) at its largest. Over all directions:
    ``max_abs_error_to_nyquist`` (``|error|``) and ``error`` (signed) at ``worst_direction`` /
    ``worst_f_cy_per_px``, the MTF measured, predicted and modelled there; ``error_sigma``: the 1-sigma of
    ``error`` as the largest of the compared points' errors (:func:`max_error_sigma` from the measured 1-sigma
    per point, ``max_abs_error_sigma`` being the one at the worst point); ``estimator_systematic`` (largest
    ``|mtf_predicted - mtf_model|``, signed, with where) and ``max_abs_error_to_model`` (the largest
    ``|measured - model|``, the check before the prediction was measured); ``prediction`` says which prediction
    was compared; the measured curves and their 1-sigma; the measurement's quality flags."""

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
    error: float | None = None
    error_sigma: float | None = None
    measured_at_worst: float | None = None
    predicted_at_worst: float | None = None
    model_at_worst: float | None = None
    estimator_systematic: float | None = None
    estimator_systematic_direction: str | None = None
    estimator_systematic_f_cy_per_px: float | None = None
    max_abs_error_to_model: float | None = None
    prediction: str | None = None
    as_built: dict | None = None


@dataclass(frozen=True)
class BarCheck(_Detail):
    """A bar target: measured CTF vs Coltman's (and the paper's Fourier-synthesis CTF) at the groups'
    frequencies (cy/px), compared up to ``compared_up_to_cy_per_px``; the MTF from the measured CTF vs the
    predicted MTF. ``ctf_measured`` is the square-wave CTF the measurement reports: the group's fitted
    modulation (``ctf_raw_measured``) plus ``ctf_correction``, the difference between the model's Coltman CTF
    and the same estimator on the group rendered through the target's joint MTF model (finite 3-bar group,
    aliased harmonics, grid phase; see measure/bars/_joint.py). ``max_abs_error_sigma`` is ``ctf_std_measured``
    at the group with the largest error (``worst_f_cy_per_px``, ``worst_group``). ``group``: each group's index in
    the target's design (the number every flag, table and file uses for it); ``at_noise_floor``: per group, whether
    its modulation was not above the noise (its CTF ~0 with its 1-sigma is measured and compared, not refused)."""

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
    group: list = field(default_factory=list)
    at_noise_floor: list = field(default_factory=list)
    worst_group: int | None = None
    as_built: dict | None = None
    # a pushbroom run: each group's CTF measured on the noise-free image of the target at the image's placement
    # (satchain.prediction.bars), what ``max_abs_error`` is taken against (written only when made)
    ctf_predicted_at_placement: list | None = None

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        if d["ctf_predicted_at_placement"] is None:
            del d["ctf_predicted_at_placement"]
        return d


@dataclass(frozen=True)
class WedgeCheck(_Detail):
    """A hyperbolic wedge: resolvable line width (ground m) measured and predicted across the stripes along
    ``axis``, the GSD (m), their ratios, and the contrast scan (``position_m`` along the wedge from its wide end,
    ``line_width_m``) measured (``contrast``) and predicted (``contrast_predicted``: the same scan on the wedge's
    noise-free predicted image, :mod:`satchain.prediction.wedge`). 1-sigma: ``resolution_m_std`` (the measured
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
    as_built: dict | None = None


@dataclass(frozen=True)
class NiirsCheck(_Detail):
    """GIQE 5 NIIRS predicted and measured, with the RER and contrast SNR each comes from;
    ``giqe5_measured_sigma``: the measured NIIRS's 1-sigma (RER and SNR sigmas through GIQE 5);
    ``snr_measured_sigma``: the measured SNR's own 1-sigma (None: it has none, the row's note says what was used)."""

    giqe5_predicted: float | None = None
    giqe5_measured: float | None = None
    rer_predicted: float | None = None
    rer_measured: float | None = None
    snr_predicted: float | None = None
    snr_measured: float | None = None
    passed: bool | None = None
    reason: str | None = None
    giqe5_measured_sigma: float | None = None
    snr_measured_sigma: float | None = None
    as_built: dict | None = None


@dataclass(frozen=True)
class Comparison:
    """The result of :func:`compare`: the checks and, per target kind, the detail the report plots.

    ``details`` maps each target kind's results.json key (``slanted_edges``, ``siemens_star``, ``bar_targets``,
    ``hyperbolic_wedge``: one per entry of the check registry, :data:`satchain.comparison.CHECKS`) to its
    per-target records, also reachable as the attributes of those names."""

    rows: tuple[CheckRow, ...]
    details: Mapping[str, tuple] = field(default_factory=dict)
    niirs: NiirsCheck = field(default_factory=NiirsCheck)
    snr_measurement: dict = field(default_factory=dict)

    @property
    def slanted_edges(self) -> tuple[EdgeCheck, ...]:
        return tuple(self.details.get(result_key(SlantedEdge.kind), ()))

    @property
    def siemens_star(self) -> tuple[StarCheck, ...]:
        return tuple(self.details.get(result_key(SiemensStar.kind), ()))

    @property
    def bar_targets(self) -> tuple[BarCheck, ...]:
        return tuple(self.details.get(result_key(BarTarget.kind), ()))

    @property
    def hyperbolic_wedge(self) -> tuple[WedgeCheck, ...]:
        return tuple(self.details.get(result_key(HyperbolicWedge.kind), ()))

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
            lines.append(f"{r.figure:{width}}  " + "  ".join(f"{cells[h]:>10}" for h in head) + f"  {cells['result']}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {
            **{key: [d.to_dict() for d in recs] for key, recs in self.details.items()},
            "niirs": self.niirs.to_dict(),
            "snr_measurement": self.snr_measurement,
            "summary": [r.to_dict() for r in self.rows],
        }


def signed_text(v: float | None, digits: int = 3) -> str:
    """``v`` with its sign and ``digits`` significant digits ("-0.00388", never "+0.00"); "-" when missing."""
    return "-" if v is None else f"{v:+.{digits}g}"


def row_texts(r: CheckRow) -> dict[str, str]:
    """A row's cells as text for the terminal: numbers to 4 significant digits, the error and z signed, and
    the result with "tolerance inside noise" when :attr:`CheckRow.tolerance_inside_noise`."""

    def num(v) -> str:
        return "-" if v is None else f"{v:.4g}"

    verdict = "n/a" if r.passed is None else ("pass" if r.passed else "FAIL")
    if r.tolerance_inside_noise:
        verdict += " (tolerance inside noise)"
    as_built = r.as_built or {}
    return {
        "measured": num(r.measured),
        "predicted": num(r.predicted),
        "error": signed_text(r.error),
        "sigma": "-" if r.sigma is None else f"{r.sigma:.2g}",
        "z": "-" if r.z is None else f"{r.z:+.2f}",
        "tolerance": r.tolerance_text,
        "result": verdict,
        "predicted as built": num(as_built.get("predicted")),
        "z as built": "-" if as_built.get("z") is None else f"{as_built['z']:+.2f}",
    }
