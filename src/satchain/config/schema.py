"""JSON Schemas of a system file, a run configuration and results.json (``satchain schema system|run|results``),
for editors (taplo / Even Better TOML: completion, hover help, validation) and other tools.

The system and run schemas come from the pydantic models (:class:`satchain.config.system.ImagingSystem`,
:class:`satchain.config.run.RunConfig`), the one source of every key: each key carries its description, its unit
and its allowed range, and a table refuses keys the loader refuses (``additionalProperties: false``), so a
misspelt key fails validation. Keys that the loader takes besides the fields (``detector.pitch_m``,
``detector.fill_factor``, ``motion.line_of_sight.file``) are accepted, and the keys that such a key stands for
(``pitch_x_m`` / ``pitch_y_m``; ``focal_length_m`` or ``f_number``) are required one way or the other.

results.json has no pydantic model: its schema is built from the typed records that write it
(:mod:`satchain.results`, :mod:`satchain.comparison.records`). It lists the documented keys and their types;
an entry may hold more keys (a renamed key is kept beside its new name for a while), so its objects stay open.

Examples
--------
>>> s = schema("system")
>>> s["additionalProperties"], "f_number" in s["$defs"]["Optics"]["properties"]
(False, True)
"""

from __future__ import annotations

import copy
import dataclasses
import re
import types
import typing
from typing import Any

__all__ = ["KINDS", "schema"]

#: The schemas ``satchain schema`` prints.
KINDS = ("system", "run", "results")

_DRAFT = "https://json-schema.org/draft/2020-12/schema"

#: The unit a key's name ends in (the house rule: the unit in every name that carries one), longest first.
_UNITS = (
    ("_px2_per_hz", "px^2/Hz"),
    ("_w_per_m2_sr_per_um", "W/(m^2 sr um)"),
    ("_m_per_s", "m/s"),
    ("_e_per_s", "electrons/s"),
    ("_cy_per_px", "cycles/px"),
    ("_waves", "waves"),
    ("_deg", "deg"),
    ("_hz", "Hz"),
    ("_px", "detector pixels"),
    ("_e", "electrons"),
    ("_s", "s"),
    ("_m", "m"),
)

#: Keys the loader takes besides a model's fields (its ``_input_keys``), with their schemas.
_INPUT_KEYS: dict[tuple[str, str], dict[str, Any]] = {
    ("Detector", "pitch_m"): {
        "type": "number",
        "exclusiveMinimum": 0,
        "maximum": 1e-3,
        "description": "pixel pitch, both axes (sets pitch_x_m and pitch_y_m)",
    },
    ("Detector", "fill_factor"): {
        "type": "number",
        "exclusiveMinimum": 0,
        "maximum": 1,
        "description": "active area fraction of a pixel (a ratio, dimensionless), a square centred in it (sets "
        "active_width_x_m and active_width_y_m)",
    },
    ("LineOfSightLog", "file"): {
        "type": "string",
        "description": "a CSV log with the columns time_s, act_px, alt_px (a header row naming them; # comments), "
        "relative to the system file; read instead of time_s, act_px, alt_px",
    },
}

#: Required fields that a before-validator may fill from other keys: one of the alternatives is required.
_ONE_OF_REQUIRED: dict[str, tuple[tuple[str, ...], list[list[str]]]] = {
    "Optics": (("focal_length_m", "f_number"), [["focal_length_m"], ["f_number"]]),
    "Detector": (
        ("pitch_x_m", "pitch_y_m", "active_width_x_m", "active_width_y_m"),
        [["pitch_m"], ["pitch_x_m", "pitch_y_m"]],
    ),
    "LineOfSightLog": (("time_s",), [["time_s"], ["file"]]),
}


def _unit(name: str) -> str | None:
    for suffix, unit in _UNITS:
        if name.endswith(suffix):
            return unit
    return None


def _range_text(prop: dict[str, Any]) -> str:
    """``"range (0, 1e+08]"`` from a property's bounds (``""`` when it has none)."""
    lo, hi = prop.get("exclusiveMinimum", prop.get("minimum")), prop.get("exclusiveMaximum", prop.get("maximum"))
    if lo is None and hi is None:
        return ""
    left = "(" if lo is None or "exclusiveMinimum" in prop else "["
    right = ")" if hi is None or "exclusiveMaximum" in prop else "]"
    return f"range {left}{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}{right}"


def _bounded(prop: dict[str, Any]) -> dict[str, Any]:
    """The part of a property that carries its bounds (a ``number | null`` keeps them in its ``anyOf``)."""
    for alt in prop.get("anyOf", ()):
        if any(k in alt for k in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum")):
            return alt
    return prop


def _annotate(name: str, prop: dict[str, Any]) -> None:
    """Add the unit (``x-unit`` and in words) and the allowed range to a property's description."""
    parts = [prop["description"]] if prop.get("description") else []
    unit = _unit(name)
    if unit is not None:
        prop["x-unit"] = unit
        if not re.search(rf"(^|[ ,(]){re.escape(unit)}([ ,)]|$)", prop.get("description", "")):
            parts.append(f"unit: {unit}")
    allowed = _range_text(_bounded(prop))
    if allowed:
        parts.append(allowed)
    if parts:
        prop["description"] = "; ".join(parts)


def _finish_model(name: str, model_schema: dict[str, Any]) -> None:
    """A model's schema made as the loader reads it: input keys, alternatives, descriptions, closed tables."""
    props = model_schema.setdefault("properties", {})
    if "description" in model_schema:  # the model's docstring, without its doctest examples
        model_schema["description"] = model_schema["description"].split("\n\nExamples\n", 1)[0].strip()
    for pname, prop in props.items():
        _annotate(pname, prop)
        prop.pop("title", None)
    for (model, key), sub in _INPUT_KEYS.items():
        if model == name:
            props[key] = copy.deepcopy(sub)
            _annotate(key, props[key])
    if name in _ONE_OF_REQUIRED:
        filled, alternatives = _ONE_OF_REQUIRED[name]
        model_schema["required"] = [r for r in model_schema.get("required", []) if r not in filled]
        if not model_schema["required"]:
            del model_schema["required"]
        model_schema["anyOf"] = [{"required": alt} for alt in alternatives]
    model_schema["additionalProperties"] = False


def _finish(top: dict[str, Any], title: str, description: str) -> dict[str, Any]:
    defs = top.get("$defs", {})
    for name, sub in defs.items():
        if sub.get("type") == "object":
            _finish_model(name, sub)
    _finish_model(top.get("title", ""), top)
    rest = {k: v for k, v in top.items() if k not in ("title", "description")}
    return {"$schema": _DRAFT, "title": title, "description": description, **rest}


def system_schema() -> dict[str, Any]:
    """The JSON Schema of a system file (:class:`satchain.config.system.ImagingSystem`)."""
    from satchain.config.system import ImagingSystem

    s = _finish(
        ImagingSystem.model_json_schema(),
        "satchain system file",
        "A satellite camera and its orbit (satchain's ImagingSystem): [orbit], [optics], [detector] and the optional "
        "[motion], [radiometry], [illumination], [atmosphere], [[bands]]. Every length is in metres.",
    )
    # one [motion.jitter_psd] table or an array of them ([[motion.jitter_psd]])
    psd = s["$defs"]["Motion"]["properties"]["jitter_psd"]
    s["$defs"]["Motion"]["properties"]["jitter_psd"] = {
        "anyOf": [{"$ref": "#/$defs/JitterPSD"}, {k: v for k, v in psd.items() if k != "description"}],
        "description": psd.get("description", ""),
    }
    # zernike_rms_waves: TOML keys are strings ("4" = 0.05): they must read as Noll indices
    zern = s["$defs"]["Optics"]["properties"]["zernike_rms_waves"]
    zern["propertyNames"] = {"pattern": "^[0-9]+$"}
    return s


def run_schema() -> dict[str, Any]:
    """The JSON Schema of a run configuration (:class:`satchain.config.run.RunConfig`); ``system.inline`` is a
    system file's content and ``as_built`` a partial one (any of its sections, keys optional)."""
    from satchain.config.run import _SYSTEM_SECTIONS, RunConfig

    s = _finish(
        RunConfig.model_json_schema(),
        "satchain run configuration",
        "One `satchain run`: [system] (a preset, a system file or an inline system), [as_built], [scene], "
        "[simulation], [measurement], [tolerances]. `satchain run --print-config` prints the defaults.",
    )
    system = system_schema()
    defs = s.setdefault("$defs", {})
    defs.update(system.pop("$defs"))
    defs["ImagingSystem"] = {k: v for k, v in system.items() if k != "$schema"}
    ref = defs["SystemRef"]["properties"]
    ref["inline"] = {
        "anyOf": [{"$ref": "#/$defs/ImagingSystem"}, {"type": "null"}],
        "description": "the system itself, as a system file holds it",
    }
    partial: dict[str, Any] = {"file": {"type": "string", "description": "a system file, relative to the config"}}
    for section in _SYSTEM_SECTIONS:
        ref_name = defs["ImagingSystem"]["properties"][section].get("$ref", "").rsplit("/", 1)[-1]
        loose = copy.deepcopy(defs[ref_name])
        loose.pop("required", None)
        loose.pop("anyOf", None)
        loose["description"] = f"[{section}] keys of the camera as built, merged over the design's"
        defs[f"AsBuilt{ref_name}"] = loose
        partial[section] = {"$ref": f"#/$defs/AsBuilt{ref_name}", "description": loose["description"]}
    desc = s["properties"]["as_built"].get("description", "")
    s["properties"]["as_built"] = {
        "anyOf": [{"type": "object", "properties": partial, "additionalProperties": False}, {"type": "null"}],
        "description": desc
        or "the camera as built: a system file (file) and/or its sections, merged over "
        "[system]; applied to the simulation only",
    }
    return s


# ------------------------------------------------------------------------------------------------- results.json
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


def _record(cls: type, *, renames: dict[str, str] | None = None, drop: tuple[str, ...] = ()) -> dict[str, Any]:
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
    from satchain.comparison.records import (
        BarCheck,
        CheckRow,
        EdgeCheck,
        NiirsCheck,
        StarCheck,
        WedgeCheck,
        result_key,
    )
    from satchain.config.run import Tolerances
    from satchain.results import RESULTS_FORMAT_VERSION
    from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

    num, opt_num = {"type": "number"}, {"type": ["number", "null"]}
    per_axis = {"type": "object", "properties": {"act": opt_num, "alt": opt_num}, "required": ["act", "alt"]}
    row = _record(CheckRow, renames={"tolerance_text": "tolerance", "tolerance": "tolerance_value"})
    row["properties"] |= {"z": opt_num, "tolerance_inside_noise": {"type": ["boolean", "null"]}}
    row["required"] += ["z", "tolerance_inside_noise"]
    tolerances = Tolerances.model_json_schema()
    for name, prop in tolerances["properties"].items():
        prop.pop("title", None)
        _annotate(name, prop)
    defs = {
        "CheckRow": row,
        "EdgeCheck": _record(EdgeCheck),
        "StarCheck": _record(StarCheck),
        "BarCheck": _record(BarCheck),
        "WedgeCheck": _record(WedgeCheck),
        "NiirsCheck": _record(NiirsCheck),
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
    }
    required = [k for k in props if k not in ("image_geometry",)]
    return {
        "$schema": _DRAFT,
        "title": "satchain results.json",
        "description": "The results of one `satchain run` (strict JSON: null, never NaN, for what is not "
        "available). Objects may hold more keys than listed (a renamed key is kept beside its new name).",
        "type": "object",
        "properties": props,
        "required": required,
        "$defs": defs,
    }


def schema(kind: str) -> dict[str, Any]:
    """The JSON Schema ``satchain schema KIND`` prints: ``"system"``, ``"run"`` or ``"results"``."""
    makers = {"system": system_schema, "run": run_schema, "results": results_schema}
    if kind not in makers:
        from satchain.errors import ConfigError

        raise ConfigError(f"schema kind = {kind!r}: must be one of {', '.join(KINDS)}")
    return makers[kind]()
