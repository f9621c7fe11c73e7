"""Issue 30, point 6: ``satchain schema system|run|results`` prints JSON Schemas, from the pydantic models, that
validate a system file, a run configuration and a results.json; a misspelt key fails them."""

from __future__ import annotations

import copy
import json
import re
import warnings
from importlib import resources
from pathlib import Path

import jsonschema
import pytest
import tomllib
from typer.testing import CliRunner

from satchain.cli.main import app

MINIMAL_SYSTEM = """
[orbit]
altitude_m = 500000
[optics]
aperture_diameter_m = 0.5
focal_length_m = 5.0
wavelengths_m = [6.5e-7]
[detector]
pitch_x_m = 5e-6
pitch_y_m = 5e-6
"""

MOTION = """
[[motion.oscillation]]
axis = "act"
amplitude_px = 0.3
frequency_hz = 40.0
[motion.jitter_psd]
axis = "alt"
frequency_hz = [1.0, 100.0]
psd_px2_per_hz = [1e-4, 1e-6]
"""


def _schema(kind: str) -> dict:
    result = CliRunner().invoke(app, ["schema", kind])
    assert result.exit_code == 0, result.output
    schema = json.loads(result.stdout)
    jsonschema.Draft202012Validator.check_schema(schema)
    return schema


def _errors(kind: str, data) -> list[str]:
    validator = jsonschema.Draft202012Validator(_schema(kind))
    return [f"{'.'.join(map(str, e.absolute_path))}: {e.message}" for e in validator.iter_errors(data)]


BUDGET = Path(__file__).resolve().parents[1] / "docs" / "guide" / "budget.md"


def _system_file_text() -> str:
    """The system file of docs/guide/budget.md ("A system file"), written there by ``cat > mycamera.toml``."""
    section = BUDGET.read_text().split("### A system file", 1)[1]
    return re.search(r"^cat > mycamera\.toml <<'EOF'\n(.*?)^EOF$", section, re.S | re.M).group(1)


def _readme_system_file() -> dict:
    return tomllib.loads(_system_file_text())


def test_the_preset_the_readme_example_and_a_minimal_system_file_validate():
    preset = tomllib.loads((resources.files("satchain.presets") / "ankarasat3.toml").read_text())
    readme = _readme_system_file()
    assert readme["detector"]["pitch_m"] and readme["detector"]["fill_factor"]  # the loader's extra keys
    for data in (preset, readme, tomllib.loads(MINIMAL_SYSTEM)):
        assert _errors("system", data) == []
    motion = tomllib.loads(MINIMAL_SYSTEM + MOTION)  # one [motion.jitter_psd] table, an array of oscillations
    assert _errors("system", motion) == []


def test_a_misspelt_or_missing_key_fails_the_system_schema():
    data = _readme_system_file()
    data["optics"]["f_numbr"] = data["optics"].pop("f_number")
    errors = _errors("system", data)
    assert any("f_numbr" in e for e in errors), errors
    minimal = tomllib.loads(MINIMAL_SYSTEM)
    del minimal["detector"]["pitch_y_m"]  # neither pitch_m nor both pitches: the loader refuses it too
    assert _errors("system", minimal)
    minimal = tomllib.loads(MINIMAL_SYSTEM)
    minimal["optics"]["obscuration_ratio"] = 1.2  # out of its range
    assert _errors("system", minimal)


def test_the_system_schema_describes_each_key_with_unit_and_range():
    orbit = _schema("system")["$defs"]["Orbit"]["properties"]["altitude_m"]
    assert orbit["x-unit"] == "m" and "range (0, 1e+08]" in orbit["description"]
    assert "height above the ground" in orbit["description"]


def test_print_config_validates_against_the_run_schema():
    out = CliRunner().invoke(app, ["run", "--print-config"])
    assert out.exit_code == 0
    config = tomllib.loads(out.stdout)
    assert _errors("run", config) == []
    assert _errors("run", {**config, "system": {"inline": _readme_system_file()}}) == []
    assert _errors("run", {**config, "as_built": {"motion": {"smear_px": 3.0}}}) == []
    assert _errors("run", {**config, "simulation": {"sede": 1}})


@pytest.fixture(scope="module")
def results_json(tmp_path_factory, reduced_scene_toml):
    import satchain
    from satchain.config.run import load_run_config

    d = tmp_path_factory.mktemp("run")
    (d / "scene.toml").write_text(reduced_scene_toml)
    (d / "run.toml").write_text('[scene]\nlayout = "scene.toml"\npixel_m = 0.07\n[simulation]\nseed = 11\n')
    with warnings.catch_warnings():  # the reduced scene's wedge is finer than its raster resolves
        warnings.simplefilter("ignore")
        satchain.run(load_run_config(d / "run.toml"), out_dir=d / "out")
    return json.loads((d / "out" / "results.json").read_text())


def test_a_real_results_json_validates_against_the_results_schema(results_json):
    assert _errors("results", results_json) == []
    assert _errors("results", {k: v for k, v in results_json.items() if k != "summary"})  # a key missing
    assert _errors("results", {**results_json, "format_version": 1})


# ------------------------------------------------------------------------------------------------- study files
STUDY_FILE = """
[base]
file = "run.toml"
[[axes]]
key = "optics.aperture_diameter_m"
values = [0.35, 0.45, 0.55, 0.70]
[[axes]]
key = "optics.wfe_rms_waves"
start = 0.0
stop = 0.1
step = 0.05
[study]
depth = "budget"
repeats = 2
zip = false
reports = "failed"
"""

INLINE_STUDY_FILE = """
[base.system]
preset = "ankarasat3"
[base.simulation]
seed = 7
[[axes]]
key = "orbit.altitude_m"
start = 450000.0
stop = 650000.0
num = 5
"""


def _loader_refuses(data: dict, tmp_path: Path) -> bool:
    from satchain.config.study import StudyFile
    from satchain.errors import ConfigError

    try:
        StudyFile.from_dict(data, base_dir=tmp_path).run_config()
    except ConfigError:
        return True
    return False


def _bad_studies() -> dict[str, dict]:
    """Study files that the loader refuses, one fault each."""
    good = tomllib.loads(STUDY_FILE)
    bad: dict[str, dict] = {}
    for name, change in {
        "unknown [study] key": lambda d: d["study"].update(deph="run"),
        "unknown top-level key": lambda d: d.update(studdy={}),
        "unknown [base] key beside file": lambda d: d["base"].update(seed=3),
        "depth = 'deep'": lambda d: d["study"].update(depth="deep"),
        "values = []": lambda d: d["axes"][0].update(values=[]),
        "values and num": lambda d: d["axes"][0].update(start=0.3, stop=0.7, num=3),
        "num and step": lambda d: d["axes"][1].update(num=3),
        "step = 0": lambda d: d["axes"][1].update(step=0.0),
        "repeats = 0": lambda d: d["study"].update(repeats=0),
        "a string value": lambda d: d["axes"][0].update(values=[0.35, "0.45"]),
        "an undotted key": lambda d: d["axes"][0].update(key="aperture"),
        "no axes": lambda d: d.update(axes=[]),
        "an unknown inline run key": lambda d: d.update(base={"simulation": {"sede": 1}}),
    }.items():
        data = copy.deepcopy(good)
        change(data)
        bad[name] = data
    return bad


def test_real_study_files_validate_against_the_study_schema(tmp_path):
    (tmp_path / "run.toml").write_text('[system]\npreset = "ankarasat3"\n')
    for text in (STUDY_FILE, INLINE_STUDY_FILE):
        data = tomllib.loads(text)
        assert not _loader_refuses(data, tmp_path)
        assert _errors("study", data) == []
    # a base with the run configuration's every default (as --print-config prints it) is a valid inline base
    config = tomllib.loads(CliRunner().invoke(app, ["run", "--print-config"]).stdout)
    assert _errors("study", {**tomllib.loads(INLINE_STUDY_FILE), "base": config}) == []


@pytest.mark.parametrize("fault", sorted(_bad_studies()))
def test_what_the_loader_refuses_fails_the_study_schema(fault, tmp_path):
    (tmp_path / "run.toml").write_text('[system]\npreset = "ankarasat3"\n')
    data = _bad_studies()[fault]
    assert _loader_refuses(data, tmp_path), fault
    assert _errors("study", data), fault


def test_the_study_schema_describes_every_study_and_axis_key():
    from satchain.config.study import Axis, StudyFile, StudySettings

    s = _schema("study")
    defs = s["$defs"]
    for model, props in (
        (Axis, defs["Axis"]["properties"]),
        (StudySettings, defs["StudySettings"]["properties"]),
        (StudyFile, s["properties"]),
    ):
        fields = {n: f for n, f in model.model_fields.items() if not f.exclude}
        assert set(props) == set(fields), model
        for name, field in fields.items():
            assert field.description and props[name]["description"].startswith(field.description), (model, name)
    # [base] is the run configuration itself (not a free table), or a file
    base = s["properties"]["base"]["anyOf"]
    assert {"$ref": "#/$defs/RunConfig"} in base
    assert defs["RunConfig"]["properties"].keys() == _schema("run")["properties"].keys()
    assert defs["StudySettings"]["properties"]["depth"]["enum"] == ["budget", "run"]
