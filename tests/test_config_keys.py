"""Issue 30, point 4: every key of a system file and of a run configuration is described in the JSON Schemas that
``satchain schema system|run`` prints (and that the docs' key reference is generated from): what it is, and its unit
when its name carries none; and the ranges that validators enforce element by element appear in the schema, so an
editor refuses what the loader refuses."""

from __future__ import annotations

import copy
import json
import re
import typing
from typing import Any

import jsonschema
import pytest
from pydantic import BaseModel
from typer.testing import CliRunner

from satchain.config.run import RunConfig
from satchain.config.schema import schema, unit_of_key
from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError

#: How a description says the unit of a key whose name carries none (``f_number``, ``tdi_stages``, ``seed``).
_UNIT_IN_WORDS = re.compile(r"\b(dimensionless|ratio|count|bits|no unit)\b|m\^-2/3")


def _own(prop: dict[str, Any]) -> str:
    """A key's own description: without the ``unit: ...`` and ``range ...`` parts the schema appends."""
    parts = str(prop.get("description", "")).split("; ")
    return "; ".join(p for p in parts if not p.startswith(("unit: ", "range "))).strip()


def _alternatives(prop: dict[str, Any]) -> list[dict[str, Any]]:
    return [prop, *prop.get("anyOf", ())]


def _ref(prop: dict[str, Any]) -> str | None:
    ref = prop.get("$ref")
    return ref.rsplit("/", 1)[-1] if isinstance(ref, str) else None


def _schema_keys(kind: str) -> dict[str, dict[str, Any]]:
    """Every key of a schema as ``section.key`` (arrays of tables as their table), nested tables included; the
    system inside a run configuration (``system.inline``) and the partial systems of ``as_built`` are the system
    file's own keys, checked with it."""
    top = schema(kind)
    defs = top.get("$defs", {})
    keys: dict[str, dict[str, Any]] = {}

    def walk(prefix: str, model: dict[str, Any]) -> None:
        for name, prop in model.get("properties", {}).items():
            key = f"{prefix}.{name}" if prefix else name
            keys[key] = prop
            if key in ("system.inline", "as_built"):
                continue
            for alt in _alternatives(prop):
                for sub in (alt, alt.get("items") if isinstance(alt.get("items"), dict) else {}):
                    ref = _ref(sub)
                    if ref is not None and ref in defs:
                        walk(key, defs[ref])

    walk("", top)
    return keys


def _model(annotation: Any) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model(arg)
        if found is not None:
            return found
    return None


def _model_keys(model: type[BaseModel], prefix: str = "") -> list[str]:
    out = []
    for name, field in model.model_fields.items():
        key = f"{prefix}.{name}" if prefix else name
        out.append(key)
        sub = _model(field.annotation)
        if sub is not None:
            out += _model_keys(sub, key)
    return out


def _is_numeric(prop: dict[str, Any]) -> bool:
    """A number, an integer, or an array or table of them."""
    for alt in _alternatives(prop):
        if alt.get("type") in ("number", "integer"):
            return True
        for inner in (alt.get("items"), alt.get("additionalProperties"), *alt.get("prefixItems", ())):
            if isinstance(inner, dict) and inner.get("type") in ("number", "integer"):
                return True
    return False


SYSTEM_KEYS = _schema_keys("system")
RUN_KEYS = _schema_keys("run")


@pytest.mark.parametrize("kind", ["system", "run"])
def test_the_cli_prints_the_schema_checked_here(kind: str) -> None:
    from satchain.cli.main import app

    result = CliRunner().invoke(app, ["schema", kind])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout) == json.loads(json.dumps(schema(kind)))


@pytest.mark.parametrize(("kind", "model"), [("system", ImagingSystem), ("run", RunConfig)])
def test_every_key_has_a_description(kind: str, model: type[BaseModel]) -> None:
    keys = SYSTEM_KEYS if kind == "system" else RUN_KEYS
    fields = [k for k in _model_keys(model) if not k.startswith(("system.inline.", "as_built."))]
    assert len(fields) > (60 if kind == "system" else 20)
    assert not [k for k in fields if k not in keys], "model fields missing from the schema"
    assert "detector.pitch_m" in SYSTEM_KEYS and "motion.line_of_sight.file" in SYSTEM_KEYS  # the loader's extras
    bare = [k for k, prop in keys.items() if len(_own(prop)) < 10]
    assert not bare, f"{kind} keys without a description: {bare}"


@pytest.mark.parametrize("kind", ["system", "run"])
def test_a_numeric_key_without_a_unit_suffix_says_its_unit(kind: str) -> None:
    keys = SYSTEM_KEYS if kind == "system" else RUN_KEYS
    unitless = {k: p for k, p in keys.items() if _is_numeric(p) and unit_of_key(k.rsplit(".", 1)[-1]) is None}
    expected = {
        "system": {"optics.f_number", "optics.transmission", "detector.tdi_stages", "optics.spiders.count",
                   "detector.qe", "atmosphere.hv_ground_cn2", "bands.wavelength_weights"},
        "run": {"simulation.seed", "tolerances.niirs", "tolerances.bar_ctf", "measurement.wedge_threshold"},
    }[kind]  # fmt: skip
    assert expected <= set(unitless)
    missing = {k: _own(p) for k, p in unitless.items() if not _UNIT_IN_WORDS.search(_own(p))}
    assert not missing, f"numeric keys whose name has no unit suffix and whose description names none: {missing}"
    for key, prop in keys.items():  # a unit suffix: the schema states the unit
        unit = unit_of_key(key.rsplit(".", 1)[-1])
        if unit is not None and _is_numeric(prop):
            assert prop.get("x-unit") == unit, key


MINIMAL = {
    "orbit": {"altitude_m": 500000.0},
    "optics": {"aperture_diameter_m": 0.5, "focal_length_m": 5.0, "wavelengths_m": [6.5e-7]},
    "detector": {"pitch_m": 5e-6},
}

#: (section, key, value the loader refuses, value it takes): ranges a validator enforces per element.
ELEMENT_RANGES = [
    ("optics", "wavelengths_m", [6.5e-7, 2e-4], [6.5e-7, 1e-4]),
    ("optics", "zernike_rms_waves", {"4": 1.5}, {"4": -1.0}),
    ("detector", "qe", 1.2, 1.0),
    ("detector", "qe", 0.0, 0.5),
    ("radiometry", "band_m", [2e-7, 9e-7], [2.8e-7, 9e-7]),
    ("motion", "line_of_sight", {"time_s": [0, 1], "act_px": [0, 1001]}, {"time_s": [0, 1], "act_px": [0, -1000]}),
    ("motion", "jitter_psd", {"axis": "act", "frequency_hz": [0, 5], "psd_px2_per_hz": [1e-6, 1e-6]},
     {"axis": "act", "frequency_hz": [1, 5], "psd_px2_per_hz": [1e-6, 0]}),
]  # fmt: skip


def _with(section: str, key: str, value: Any) -> dict[str, Any]:
    data = copy.deepcopy(MINIMAL)
    data.setdefault(section, {})[key] = value
    return data


@pytest.mark.parametrize(("section", "key", "bad", "good"), ELEMENT_RANGES)
def test_a_range_a_validator_enforces_is_in_the_schema(section: str, key: str, bad: Any, good: Any) -> None:
    validator = jsonschema.Draft202012Validator(schema("system"))
    assert list(validator.iter_errors(_with(section, key, good))) == []
    ImagingSystem.from_dict(_with(section, key, good))
    assert list(validator.iter_errors(_with(section, key, bad))), f"{section}.{key} = {bad!r} passes the schema"
    with pytest.raises(ConfigError):
        ImagingSystem.from_dict(_with(section, key, bad))


def test_a_qe_table_is_bounded_per_element() -> None:
    validator = jsonschema.Draft202012Validator(schema("system"))
    table = {"qe": [0.5, 1.2], "qe_wavelengths_m": [5e-7, 6e-7]}
    data = copy.deepcopy(MINIMAL)
    data["detector"].update(table)
    assert list(validator.iter_errors(data))
    with pytest.raises(ConfigError, match=r"qe\[1\] = 1.2: must be in \[0, 1\]"):
        ImagingSystem.from_dict(data)
    data["detector"]["qe"] = [0.0, 1.0]
    assert list(validator.iter_errors(data)) == []
    ImagingSystem.from_dict(data)
