"""The run's result types (satchain.results): fully typed, the typed truth travels, the old names still work."""

from __future__ import annotations

import dataclasses
import importlib
import json
import math
import types
import typing

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import satchain
from satchain import results
from satchain.scene import Scene, SiemensStar, SlantedEdge
from satchain.scene.truth import EdgeTruth, StarTruth, Truth, read_truth

RESULT_TYPES = (
    results.BudgetResult,
    results.SceneResult,
    results.SimulationResult,
    results.Measurements,
    results.RunResult,
)


#: The names results.py imports only for type checkers, and where they live.
TYPE_NAMES = {
    "Comparison": "satchain.comparison",
    "SensorModel": "satchain.engine.sensor",
    "Simulator": "satchain.engine.simulate",
    "AutoResult": "satchain.measure.auto",
    "SnrResult": "satchain.measure.snr",
    "Predictions": "satchain.prediction.core",
    "RunConfig": "satchain.config.run",
    "ImageScene": "satchain.scene",
    "Scene": "satchain.scene",
    "Truth": "satchain.scene.truth",
    "ImagingSystem": "satchain.config.system",
    "SystemOTF": "satchain.tf.budget",
}


def resolved_hints(cls) -> dict[str, typing.Any]:
    """The field types of ``cls`` with its TYPE_CHECKING-only names imported for real."""
    ns = {name: getattr(importlib.import_module(mod), name) for name, mod in TYPE_NAMES.items()}
    return typing.get_type_hints(cls, localns=ns)


@pytest.mark.parametrize("cls", RESULT_TYPES, ids=lambda c: c.__name__)
def test_every_field_has_a_real_type(cls):
    hints = resolved_hints(cls)
    for f in dataclasses.fields(cls):
        assert hints[f.name] is not typing.Any, f"{cls.__name__}.{f.name} is Any"


def test_the_field_types_are_the_classes_the_stages_produce():
    from satchain.config.system import ImagingSystem
    from satchain.measure.auto import AutoResult
    from satchain.measure.snr import SnrResult
    from satchain.tf.budget import SystemOTF

    assert resolved_hints(results.BudgetResult)["system"] is ImagingSystem
    assert resolved_hints(results.BudgetResult)["otf"] is SystemOTF
    assert resolved_hints(results.SceneResult)["truth"] is Truth
    assert resolved_hints(results.Measurements)["snr"] is SnrResult
    assert resolved_hints(results.Measurements)["auto"] is AutoResult


def test_the_old_import_paths_still_resolve():
    from satchain import api

    for name in ("BudgetResult", "SceneResult", "SimulationResult", "Measurements", "RunResult", "strict_json"):
        assert getattr(api, name) is getattr(results, name)
    assert satchain.RunResult is results.RunResult
    assert api.RESULTS_FORMAT_VERSION == results.RESULTS_FORMAT_VERSION == 2


@pytest.fixture(scope="module")
def small_scene():
    edge = SlantedEdge("e", center_m=(15.0, 15.0), size_m=20.0)
    items = (edge, SiemensStar("s", center_m=(45.0, 15.0), radius_m=12.0))
    return Scene(60.0, 30.0, items, pixel_m=0.25)


def test_scene_result_carries_the_typed_truth_and_gives_back_the_record(small_scene):
    record = small_scene.truth()
    sr = results.SceneResult(small_scene, record, 0.25)  # the dict form is read at the edge
    assert isinstance(sr.truth, Truth)
    assert isinstance(sr.truth["e"], EdgeTruth) and isinstance(sr.truth["s"], StarTruth)
    assert sr.truth["e"].angle_deg == record["items"][0]["angle_deg"]
    assert sr.truth_dict == record  # lossless, and what scene.truth.json holds
    assert json.loads(json.dumps(sr.truth_dict)) == record
    typed = read_truth(record)
    assert results.SceneResult(small_scene, typed, 0.25).truth is typed  # a Truth is kept as is


def test_typed_truth_is_a_deprecated_alias(small_scene):
    sr = results.SceneResult(small_scene, small_scene.truth(), 0.25)
    with pytest.warns(DeprecationWarning, match=r"typed_truth is deprecated in satchain 0\.1 .* removed in 0\.2"):
        assert sr.typed_truth is sr.truth


def test_scene_result_refuses_a_record_that_is_not_a_truth_record(small_scene):
    with pytest.raises(satchain.InputError, match="truth format"):
        results.SceneResult(small_scene, {"format": "other", "items": []}, 0.25)


json_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**6), 10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=5),
)
json_tree = st.recursive(
    json_leaf,
    lambda kids: st.one_of(st.lists(kids, max_size=4), st.dictionaries(st.text(max_size=4), kids, max_size=4)),
    max_leaves=20,
)


@given(json_tree)
def test_strict_json_always_dumps_strictly_and_keeps_every_finite_value(value):
    out = results.strict_json(value)
    text = json.dumps(out, allow_nan=False)  # raises on any NaN / inf left behind

    def same(a, b):
        if isinstance(a, float) and not math.isfinite(a):
            return b is None
        if isinstance(a, dict):
            return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
        if isinstance(a, list):
            return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
        return a == b and type(a) is type(b)

    assert same(value, json.loads(text))


def test_strict_json_makes_numpy_plain():
    out = results.strict_json({"a": np.float32(0.5), "b": np.arange(3), "c": np.bool_(True), "d": np.float64("inf")})
    assert out == {"a": 0.5, "b": [0, 1, 2], "c": True, "d": None}
    assert type(out["a"]) is float and type(out["b"][0]) is int and type(out["c"]) is bool


TINY_SCENE_TOML = """
[scene]
width_m = 40.0
height_m = 40.0
background = 0.2
pixel_m = 0.07

[[items]]
kind = "slanted_edge"
id = "e"
center_m = [20.0, 20.0]
angle_deg = 6.0
measures = "act"
size_m = 25.0
"""


def test_a_run_fills_every_field_with_its_declared_type(tmp_path):
    (tmp_path / "scene.toml").write_text(TINY_SCENE_TOML)
    result = satchain.run({"scene": {"layout": str(tmp_path / "scene.toml"), "pixel_m": 0.07}})
    for obj in (result, result.budget, result.scene, result.simulation, result.measurements):
        for name, hint in resolved_hints(type(obj)).items():
            origin = typing.get_origin(hint)
            allowed = typing.get_args(hint) if origin in (typing.Union, types.UnionType) else (origin or hint,)
            assert isinstance(getattr(obj, name), allowed), f"{type(obj).__name__}.{name}: {hint}"
    assert result.scene.truth_dict["items"][0]["id"] == "e"
    assert result.to_json_dict()["format_version"] == 2
