"""JSON Schemas of a system file, a run configuration, a study file and results.json (``satchain schema
system|run|study|results``), for editors (taplo / Even Better TOML: completion, hover help, validation) and other
tools.

The system and run schemas come from the pydantic models (:class:`satchain.config.system.ImagingSystem`,
:class:`satchain.config.run.RunConfig`), the one source of every key: each key carries its description, its unit
and its allowed range, and a table refuses keys the loader refuses (``additionalProperties: false``), so a
misspelt key fails validation. Keys that the loader takes besides the fields (``detector.pitch_m``,
``detector.fill_factor``, ``motion.line_of_sight.file``) are accepted, and the keys that such a key stands for
(``pitch_x_m`` / ``pitch_y_m``; ``focal_length_m`` or ``f_number``) are required one way or the other. The study
file's schema (:class:`satchain.config.study.StudyFile`) holds the run configuration's: its ``[base]`` is a run
configuration inline, or ``file = "run.toml"``.

results.json has no pydantic model: its schema is built, a layer above, from the typed records that write it
(:func:`satchain.results.results_schema`); ``satchain schema results`` prints it.

Examples
--------
>>> s = schema("system")
>>> s["additionalProperties"], "f_number" in s["$defs"]["Optics"]["properties"]
(False, True)
"""

from __future__ import annotations

import copy
import re
from typing import Any

__all__ = ["DRAFT", "KINDS", "annotate_key", "run_schema", "schema", "study_schema", "system_schema", "unit_of_key"]

#: The configuration schemas (``satchain schema`` prints these and results.json's).
KINDS = ("system", "run", "study")

#: The JSON Schema dialect of every schema satchain writes.
DRAFT = "https://json-schema.org/draft/2020-12/schema"

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
    ("_mm", "mm"),
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


def unit_of_key(name: str) -> str | None:
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


def annotate_key(name: str, prop: dict[str, Any]) -> None:
    """Add the unit (``x-unit`` and in words) and the allowed range to a property's description."""
    parts = [prop["description"]] if prop.get("description") else []
    unit = unit_of_key(name)
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
        annotate_key(pname, prop)
        prop.pop("title", None)
    for (model, key), sub in _INPUT_KEYS.items():
        if model == name:
            props[key] = copy.deepcopy(sub)
            annotate_key(key, props[key])
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
    return {"$schema": DRAFT, "title": title, "description": description, **rest}


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


def _axis_forms(axis: dict[str, Any]) -> None:
    """An axis gives its values one way: ``values``, or ``start``/``stop``/``num``, or ``start``/``stop``/``step``
    (the others absent, as :class:`satchain.config.study.Axis` refuses them); a listed axis is not empty and a
    step is not zero."""

    def without(*keys: str) -> dict[str, Any]:
        return {"not": {"anyOf": [{"required": [k]} for k in keys]}}

    axis["anyOf"] = [
        {"required": ["values"], **without("start", "stop", "num", "step")},
        {"required": ["start", "stop", "num"], **without("values", "step")},
        {"required": ["start", "stop", "step"], **without("values", "num")},
    ]
    props = axis["properties"]
    for alt in props["values"]["anyOf"]:
        if alt.get("type") == "array":
            alt["minItems"] = 1
    for alt in props["step"]["anyOf"]:
        if alt.get("type") == "number":
            alt["not"] = {"const": 0}
    # a dotted key '<section>.<key>', each part not blank (as the loader checks it)
    props["key"]["pattern"] = r"^[^.]*[^.\s][^.]*(\.[^.]*[^.\s][^.]*)+$"
    props["key"]["examples"] = ["optics.aperture_diameter_m", "optics.wfe_rms_waves", "orbit.altitude_m"]


def study_schema() -> dict[str, Any]:
    """The JSON Schema of a study file (:class:`satchain.config.study.StudyFile`); ``[base]`` is a run
    configuration (the run schema, under ``$defs/RunConfig``) or ``file = "run.toml"``."""
    from satchain.config.study import StudyFile

    s = _finish(
        StudyFile.model_json_schema(),
        "satchain study file",
        "A design study (`satchain study STUDY.toml -o DIR`): [base] (the run configuration the cases start "
        "from, inline or file = 'run.toml'), one or more [[axes]] (a key and its values) and [study] (depth, "
        "repeats, zip, reports).",
    )
    s["properties"].pop("base_dir", None)  # the study file's folder, set by the loader, not a key of the file
    s["properties"]["axes"]["minItems"] = 1
    defs = s.setdefault("$defs", {})
    _axis_forms(defs["Axis"])
    run = run_schema()
    run_defs = run.pop("$defs")
    clash = sorted(set(run_defs) & set(defs))
    if clash:  # pragma: no cover - a model renamed into a clash must be caught by the tests, not merged
        raise RuntimeError(f"study schema: $defs {clash} are in both the study and the run schema")
    defs.update(run_defs)
    defs["RunConfig"] = {k: v for k, v in run.items() if k != "$schema"}
    base = s["properties"]["base"]
    s["properties"]["base"] = {
        "anyOf": [
            {"$ref": "#/$defs/RunConfig"},
            {
                "type": "object",
                "properties": {
                    "file": {"type": "string", "description": "a run configuration file, relative to the study file"}
                },
                "required": ["file"],
                "additionalProperties": False,
            },
        ],
        "description": base.get("description", ""),
    }
    return s


def schema(kind: str) -> dict[str, Any]:
    """The JSON Schema of a configuration file: ``"system"``, ``"run"`` or ``"study"`` (``satchain schema
    results`` prints :func:`satchain.results.results_schema`)."""
    makers = {"system": system_schema, "run": run_schema, "study": study_schema}
    if kind not in makers:
        from satchain.errors import ConfigError

        raise ConfigError(f"schema kind = {kind!r}: must be one of {', '.join(KINDS)}")
    return makers[kind]()
