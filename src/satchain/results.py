"""The typed results that the stages of a run hand each other, and results.json's layout.

:func:`satchain.run` (:mod:`satchain.api`) and the stages (:mod:`satchain.pipeline`) both use these types;
they live here so that imports flow one way (``api -> pipeline -> results``), never in a circle. Every field
is typed; the types of other modules are imported only for type checkers, so importing this module stays
cheap (numpy only).

The truth record travels typed (:class:`satchain.scene.truth.Truth`); its JSON dict
(:attr:`SceneResult.truth_dict`) is made only at the edges that read or write the file form.

Examples
--------
>>> strict_json({"pass": True, "mtf": np.float64("nan")})
{'pass': True, 'mtf': None}
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from satchain.comparison import CheckRow, Comparison
    from satchain.config.run import RunConfig
    from satchain.config.system import ImagingSystem
    from satchain.engine.sensor import SensorModel
    from satchain.engine.simulate import Simulator
    from satchain.measure.auto import AutoResult
    from satchain.measure.snr import SnrResult
    from satchain.prediction.core import Predictions
    from satchain.scene import ImageScene, Scene
    from satchain.scene.truth import Truth
    from satchain.tf.budget import SystemOTF

__all__ = [
    "NULL_MEANING",
    "RESULTS_FORMAT_VERSION",
    "BudgetResult",
    "FocalSection",
    "Measurements",
    "RunResult",
    "SceneResult",
    "SimulationResult",
    "results_schema",
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


@dataclass(frozen=True)
class BudgetResult:
    """The predicted budget: ``system``, ``otf`` (its SystemOTF) and ``budget`` (the dict of
    :func:`satchain.prediction.budget.budget_results`: derived quantities, MTF/CTF tables, MTF at Nyquist, MTFA,
    radiometry, GIQE)."""

    system: ImagingSystem
    otf: SystemOTF = field(repr=False)
    budget: Mapping[str, Any] = field(repr=False)


@dataclass(frozen=True)
class SceneResult:
    """The ground truth: ``scene`` (a :class:`satchain.scene.Scene`), ``truth`` (its typed truth record,
    :class:`satchain.scene.truth.Truth`, positions in scene metres) and ``pixel_m`` (ground-truth pixel
    size, m). A truth record given as a dict (the JSON form) is read into a :class:`Truth`."""

    scene: Scene | ImageScene = field(repr=False)
    truth: Truth = field(repr=False)
    pixel_m: float

    def __post_init__(self) -> None:
        from satchain.scene.truth import Truth, read_truth

        if not isinstance(self.truth, Truth):
            object.__setattr__(self, "truth", read_truth(self.truth))

    @property
    def truth_dict(self) -> dict[str, Any]:
        """The truth record in its JSON form (``*.truth.json``; what ``Scene.truth()`` returns)."""
        return self.truth.to_dict()

    @property
    def typed_truth(self) -> Truth:
        """Deprecated in satchain 0.1 (to be removed in 0.2): ``truth`` is the typed record now."""
        warnings.warn(
            "SceneResult.typed_truth is deprecated in satchain 0.1 and will be removed in 0.2: "
            "SceneResult.truth is the typed Truth now (SceneResult.truth_dict is the JSON form)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.truth


@dataclass(frozen=True)
class SimulationResult:
    """The simulated images.

    ``image``: the satellite image (``units``: dn, electrons, radiance or reflectance), one pixel per GSD;
    ``focal_plane``: scene reflectance filtered by optics and motion, sampled every ``focal_plane_pixel_m``
    ground metres; ``sensor``: the SensorModel; ``simulator``: the Simulator (its ``D`` is the decimation);
    ``system``: the camera simulated (the config's ``as_built`` when it has one, else the design).
    """

    image: np.ndarray = field(repr=False)
    focal_plane: np.ndarray = field(repr=False)
    focal_plane_pixel_m: float
    units: str
    sensor: SensorModel = field(repr=False)
    simulator: Simulator = field(repr=False)
    system: ImagingSystem | None = field(default=None, repr=False)


@dataclass(frozen=True)
class Measurements:
    """``auto``: every target measured (:class:`satchain.measure.auto.AutoResult`); ``snr``: the GIQE contrast
    SNR measured on the image (:class:`satchain.measure.snr.SnrResult`)."""

    auto: AutoResult
    snr: SnrResult

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
class FocalSection:
    """One part of the focal plane as flown that a run formed, measured and compared beside its main image
    (:mod:`satchain.focal`: the bands of a ``[[bands]]`` system, the colour planes of a ``[detector] cfa``, the
    combined grid of a staggered layout).

    ``key``: its results.json key and the report's sub-section (``bands``, ``cfa``, ``staggered``); ``title``:
    its heading; ``rows``: its checks, which join the run's (the summary table, ``pass``, the exit status);
    ``data``: results.json's ``key`` entry (plain JSON: what the report's tables and figures are drawn from,
    :mod:`satchain.report.focal_plane`); ``write_files(out_dir)``: writes its rasters into the run folder (paths
    relative to it, under ``images/``) and returns them, or None when it writes none."""

    key: str
    title: str
    rows: tuple[CheckRow, ...]
    data: Mapping[str, Any]
    write_files: Callable[[Path], list[str]] | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class RunResult:
    """Everything one run produced, in memory. ``passed``: False if any check failed, None if none could be
    evaluated, True otherwise. ``to_json_dict()`` is the content of results.json. ``kept_files``: the files (and
    empty folders, ``/``-ended) of the run folder it replaced that satchain did not write, kept (relative paths)."""

    config: RunConfig
    budget: BudgetResult
    scene: SceneResult
    simulation: SimulationResult
    measurements: Measurements
    predictions: Predictions
    comparison: Comparison
    timings_s: Mapping[str, float] = field(default_factory=dict)
    kept_files: tuple[str, ...] = ()
    #: the focal plane as flown (bands, colour planes, staggered arrays), formed and compared beside the image;
    #: their rows are already in ``comparison``
    focal: tuple[FocalSection, ...] = ()

    def __repr__(self) -> str:  # short: the full objects are a click away in a notebook
        c, img = self.comparison, self.simulation.image
        return (
            f"RunResult(system={self.system.name!r}, passed={self.passed}, checks={c.n_checked - c.n_failed}/"
            f"{c.n_checked} pass ({len(c.rows) - c.n_checked} n/a), image={img.shape[0]}x{img.shape[1]} px "
            f"{self.simulation.units})"
        )

    @property
    def system(self) -> ImagingSystem:
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
        from satchain.config.run import system_differences

        out["as_built_differences"] = system_differences(s, self.simulation.system) if self.config.as_built else []
        out.update(c.to_dict())
        out["skipped"] = list(self.measurements.auto.skipped)
        out["tolerances"] = self.config.tolerances.model_dump()
        from satchain.prediction.image_geometry import geometry_table

        geometry = geometry_table(self.simulation.system or s)  # pushbroom motion: its inputs and geometry
        if geometry:
            out["image_geometry"] = geometry
        for sec in self.focal:
            out[sec.key] = dict(sec.data)
        return strict_json(out)


# ------------------------------------------------------------------------------------------------- its schema
def _of_type(tp: Any) -> dict[str, Any]:
    """A JSON Schema from a record's type hint (``float | None``, ``list``, ``dict[str, Any]`` ...)."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        return {"anyOf": [_of_type(a) for a in typing.get_args(tp)]}
    if tp is type(None):
        return {"type": "null"}
    if tp is bool:
        return {"type": "boolean"}
    if tp is int:
        return {"type": "integer"}
    if tp is float:
        return {"type": "number"}
    if tp is str:
        return {"type": "string"}
    if tp in (list, tuple) or origin in (list, tuple):
        return {"type": "array"}
    if tp is dict or origin in (dict, typing.get_origin(typing.Mapping)):
        return {"type": "object"}
    return {}


def _record_schema(cls: type, *, renames: dict[str, str] | None = None, drop: tuple[str, ...] = ()) -> dict[str, Any]:
    """The schema of a record dataclass as its ``to_dict`` writes it (``passed`` as ``pass``); fields with a
    default may be left out."""
    renames = {"passed": "pass", **(renames or {})}
    hints = typing.get_type_hints(cls)
    props: dict[str, Any] = {}
    required: list[str] = []
    for f in dataclasses.fields(cls):
        if f.name in drop:
            continue
        key = renames.get(f.name, f.name)
        props[key] = _of_type(hints[f.name])
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            required.append(key)
    return {"type": "object", "properties": props, "required": required}


def results_schema() -> dict[str, Any]:
    """The JSON Schema of results.json (:meth:`satchain.results.RunResult.to_json_dict`)."""
    from satchain.comparison.records import (  # the records that write the file
        BarCheck,
        CheckRow,
        EdgeCheck,
        NiirsCheck,
        StarCheck,
        WedgeCheck,
        result_key,
    )
    from satchain.config.run import Tolerances
    from satchain.config.schema import DRAFT, annotate_key
    from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

    num, opt_num = {"type": "number"}, {"type": ["number", "null"]}
    per_axis = {"type": "object", "properties": {"act": opt_num, "alt": opt_num}, "required": ["act", "alt"]}
    row = _record_schema(CheckRow, renames={"tolerance_text": "tolerance", "tolerance": "tolerance_value"})
    row["properties"] |= {"z": opt_num, "tolerance_inside_noise": {"type": ["boolean", "null"]}}
    row["required"] += ["z", "tolerance_inside_noise"]
    tolerances = Tolerances.model_json_schema()
    for name, prop in tolerances["properties"].items():
        prop.pop("title", None)
        annotate_key(name, prop)
    defs = {
        "CheckRow": row,
        "EdgeCheck": _record_schema(EdgeCheck),
        "StarCheck": _record_schema(StarCheck),
        "BarCheck": _record_schema(BarCheck),
        "WedgeCheck": _record_schema(WedgeCheck),
        "NiirsCheck": _record_schema(NiirsCheck),
        "Tolerances": {k: v for k, v in tolerances.items() if k != "title"},
    }
    props: dict[str, Any] = {
        "format_version": {"const": RESULTS_FORMAT_VERSION, "description": "version of the results.json layout"},
        "pass": {"type": ["boolean", "null"], "description": "overall: false if a check failed, null if none ran"},
        "n_checks": {"type": "integer", "minimum": 0},
        "n_checked": {"type": "integer", "minimum": 0},
        "n_failed": {"type": "integer", "minimum": 0},
        "null_means": {"type": "string"},
        "warnings": {"type": "array", "items": {"type": "string"}},
        "system": {"type": "string", "description": "the system's name"},
        "gsd_m": {**num, "x-unit": "m"},
        "gsd_act_m": {**num, "x-unit": "m"},
        "gsd_alt_m": {**num, "x-unit": "m"},
        "mtf_at_nyquist": {**per_axis, "description": "predicted system MTF at Nyquist"},
        "mtfa": {**per_axis, "description": "predicted MTF area"},
        "radiometry": {
            "type": "object",
            "properties": {k: opt_num for k in ("signal_e", "snr", "contrast_snr", "well_fill")}
            | {"saturated": {"type": ["boolean", "null"]}},
        },
        "quality_predicted": {"type": "object", "description": "GIQE inputs and NIIRS predicted"},
        "as_built_differences": {"type": "array"},
        result_key(SlantedEdge.kind): {"type": "array", "items": {"$ref": "#/$defs/EdgeCheck"}},
        result_key(SiemensStar.kind): {"type": "array", "items": {"$ref": "#/$defs/StarCheck"}},
        result_key(BarTarget.kind): {"type": "array", "items": {"$ref": "#/$defs/BarCheck"}},
        result_key(HyperbolicWedge.kind): {"type": "array", "items": {"$ref": "#/$defs/WedgeCheck"}},
        "niirs": {"$ref": "#/$defs/NiirsCheck"},
        "snr_measurement": {"type": "object"},
        "summary": {"type": "array", "items": {"$ref": "#/$defs/CheckRow"}, "description": "one row per check"},
        "skipped": {"type": "array"},
        "tolerances": {"$ref": "#/$defs/Tolerances"},
        "image_geometry": {"type": "object", "description": "pushbroom image geometry (a time-varying motion)"},
        "bands": {"type": "object", "description": "every band of a [[bands]] system: per-band edge MTF at its "
                  "Nyquist, SNR and registration to the PAN band against the budget (satchain.focal.bands)"},
        "cfa": {"type": "object", "description": "a colour filter array: each raw colour plane's MTF against its "
                "prediction, and each demosaicing method's luminance MTF50 and false colour (satchain.focal.cfa)"},
        "staggered": {"type": "object", "description": "a staggered layout: the combined grid's edges and bars "
                      "against the prediction (satchain.focal.staggered)"},
    }
    optional = ("image_geometry", "bands", "cfa", "staggered")
    required = [k for k in props if k not in optional]
    return {
        "$schema": DRAFT,
        "title": "satchain results.json",
        "description": "The results of one `satchain run` (strict JSON: null, never NaN, for what is not "
        "available). Objects may hold more keys than listed (a renamed key is kept beside its new name).",
        "type": "object",
        "properties": props,
        "required": required,
        "$defs": defs,
    }
