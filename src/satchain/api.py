"""The notebook entry point: :func:`run` and the typed results that the stages of a run hand each other.

>>> import satchain
>>> result = satchain.run({"scene": {"layout": "my_scene.toml"}})       # doctest: +SKIP
>>> result.passed, result.simulation.image.shape                        # doctest: +SKIP
>>> [(r.figure, r.measured, r.predicted, r.passed) for r in result.comparison.rows]  # doctest: +SKIP

Stages: budget (prediction of MTF, CTF, radiometry, SNR, GIQE) -> scene (ground truth and its truth record) ->
simulation (the satellite image and the focal-plane image, in memory) -> measurement (every target, and the
SNR) -> prediction of what each measurement should give -> comparison. Nothing is written unless ``out_dir``
is given (``satchain run`` gives it): then the run directory (report.html, results.json, images, figures,
manifest.json) is written atomically, see :mod:`satchain.pipeline`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from satchain.comparison import Comparison
from satchain.prediction import Predictions
from satchain.runconfig import RunConfig

__all__ = [
    "RESULTS_FORMAT_VERSION",
    "BudgetResult",
    "Measurements",
    "RunResult",
    "SceneResult",
    "SimulationResult",
    "as_run_config",
    "run",
    "strict_json",
]

#: Version of the results.json layout (2: strict JSON, ``format_version``, overall ``pass``, n/a rows).
RESULTS_FORMAT_VERSION = 2
#: What a null in results.json means.
NULL_MEANING = (
    "null = not available: the quantity could not be measured or computed (target not measurable at this pixel "
    "size, clipped, nothing in the compared range, or a prediction that does not exist); a check with a null "
    "measurement is n/a (pass = null) and its 'reason' says why"
)
Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class BudgetResult:
    """The predicted budget: ``system`` (ImagingSystem), ``otf`` (SystemOTF) and ``budget`` (the dict of
    :func:`satchain.report.budget.budget_results`: derived quantities, MTF/CTF tables, MTF at Nyquist, MTFA,
    radiometry, GIQE)."""

    system: Any
    otf: Any = field(repr=False)
    budget: Mapping[str, Any] = field(repr=False)


@dataclass(frozen=True)
class SceneResult:
    """The ground truth: ``scene`` (a :class:`satchain.scene.Scene`), ``truth`` (its truth record, a dict in
    scene metres) and ``pixel_m`` (ground-truth pixel size, m)."""

    scene: Any = field(repr=False)
    truth: Mapping[str, Any] = field(repr=False)
    pixel_m: float

    @property
    def typed_truth(self):
        """The truth record as a typed :class:`satchain.scene.truth.Truth`."""
        from satchain.scene.truth import read_truth

        return read_truth(self.truth)


@dataclass(frozen=True)
class SimulationResult:
    """The simulated images.

    ``image``: the satellite image (``units``: dn, electrons, radiance or reflectance), one pixel per GSD;
    ``focal_plane``: scene reflectance filtered by optics and motion, sampled every ``focal_plane_pixel_m``
    ground metres; ``sensor``: the SensorModel; ``simulator``: the Simulator (its ``D`` is the decimation).
    """

    image: np.ndarray = field(repr=False)
    focal_plane: np.ndarray = field(repr=False)
    focal_plane_pixel_m: float
    units: str
    sensor: Any = field(repr=False)
    simulator: Any = field(repr=False)


@dataclass(frozen=True)
class Measurements:
    """``auto``: every target measured (:class:`satchain.measure.auto.AutoResult`); ``snr``: the GIQE contrast
    SNR measured on the image (:class:`satchain.measure.snr.SnrResult`)."""

    auto: Any
    snr: Any

    def to_dict(self) -> dict[str, Any]:
        return {**self.auto.to_dict(), "snr": self.snr.to_dict()}


def strict_json(value: Any) -> Any:
    """``value`` with numpy types made plain and every NaN/inf replaced by None (so ``json.dumps(...,
    allow_nan=False)`` succeeds).

    Examples
    --------
    >>> strict_json({"a": np.float64("nan"), "b": [np.int64(2), float("inf")], "c": (1.5,)})
    {'a': None, 'b': [2, None], 'c': [1.5]}
    """
    if isinstance(value, Mapping):
        return {str(k): strict_json(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return strict_json(value.tolist())
    if isinstance(value, (list, tuple)):
        return [strict_json(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


@dataclass(frozen=True)
class RunResult:
    """Everything one run produced, in memory. ``passed``: False if any check failed, None if none could be
    evaluated, True otherwise. ``to_json_dict()`` is the content of results.json."""

    config: RunConfig
    budget: BudgetResult
    scene: SceneResult
    simulation: SimulationResult
    measurements: Measurements
    predictions: Predictions
    comparison: Comparison
    timings_s: Mapping[str, float] = field(default_factory=dict)

    def __repr__(self) -> str:  # short: the full objects are a click away in a notebook
        c, img = self.comparison, self.simulation.image
        return (
            f"RunResult(system={self.system.name!r}, passed={self.passed}, checks={c.n_checked - c.n_failed}/"
            f"{c.n_checked} pass ({len(c.rows) - c.n_checked} n/a), image={img.shape[0]}x{img.shape[1]} px "
            f"{self.simulation.units})"
        )

    @property
    def system(self):
        return self.budget.system

    @property
    def passed(self) -> bool | None:
        return self.comparison.passed

    @property
    def warnings(self) -> tuple[str, ...]:
        return tuple(self.predictions.warnings) + tuple(self.measurements.auto.warnings)

    def to_json_dict(self) -> dict[str, Any]:
        """results.json: strict JSON (nulls, never NaN), with ``format_version`` and the overall ``pass``."""
        s, b, c = self.system, self.budget.budget, self.comparison
        out: dict[str, Any] = {
            "format_version": RESULTS_FORMAT_VERSION,
            "pass": c.passed,
            "n_checks": len(c.rows),
            "n_checked": c.n_checked,
            "n_failed": c.n_failed,
            "null_means": NULL_MEANING,
            "warnings": list(self.warnings),
            "system": s.name,
            "gsd_m": s.gsd_m,
            "gsd_act_m": s.gsd_act_m,
            "gsd_alt_m": s.gsd_alt_m,
            "mtf_at_nyquist": b["mtf_at_nyquist"],
            "mtfa": b["mtfa"],
            "radiometry": {
                k: b["radiometry"][k] for k in ("signal_e", "snr", "contrast_snr", "well_fill", "saturated")
            },
            "quality_predicted": b["quality"],
        }
        out.update(c.to_dict())
        out["skipped"] = list(self.measurements.auto.skipped)
        out["tolerances"] = self.config.tolerances.model_dump()
        return strict_json(out)


def as_run_config(config: RunConfig | Mapping[str, Any] | str | Path | None) -> RunConfig:
    """A RunConfig from a RunConfig, a dict (as in the TOML), a TOML path, or None (the defaults)."""
    import os

    from satchain.errors import ParameterTypeError
    from satchain.runconfig import load_run_config

    if isinstance(config, RunConfig):
        return config
    if isinstance(config, Mapping):
        return RunConfig.from_dict(dict(config))
    if config is not None and not isinstance(config, (str, Path, os.PathLike)):
        shown = repr(config) if len(repr(config)) <= 60 else repr(config)[:57] + "..."
        raise ParameterTypeError(
            f"run(): config = {shown}: must be a RunConfig, a dict (as in the TOML), a TOML path or None"
        )
    return load_run_config(config)


from satchain._argcheck import checked  # noqa: E402  (here, beside its one use: the types above stay apart)


@checked
def run(
    config: RunConfig | Mapping[str, Any] | str | Path | None = None,
    *,
    out_dir: str | Path | None = None,
    progress: Progress | None = None,
) -> RunResult:
    """Predict, simulate, measure and compare; write the run directory only when ``out_dir`` is given.

    Parameters
    ----------
    config : RunConfig, dict, path or None
        The run configuration (``satchain run --print-config`` shows every key); None: the defaults (the
        reference paper's camera and scene, which takes a minute or two).
    out_dir : path, optional
        Write report.html, results.json, images, figures and manifest.json there (replaced atomically; an
        existing directory must be a satchain run directory).
    progress : callable, optional
        ``progress(stage, done, total)``, stage one of :data:`satchain.pipeline.STAGES`.

    Returns
    -------
    RunResult
    """
    from satchain import pipeline

    cfg = as_run_config(config)
    if out_dir is None:
        return pipeline.run_in_memory(cfg, progress=progress)
    return pipeline.run_to_directory(cfg, out_dir, progress=progress)
