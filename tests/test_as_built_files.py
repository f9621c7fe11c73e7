"""[as_built] file = a complete system file (docs/guide/budget.md's, the preset's, the run's own) or a partial one;
fill factor and active widths in either file (issue 29, item 2: these raised KeyError 'active_width_x_m')."""

from __future__ import annotations

import math
import re
from importlib import resources
from pathlib import Path

import pytest

from satchain.config.run import RunConfig, system_differences
from satchain.config.system import ImagingSystem, load_preset

BUDGET = Path(__file__).resolve().parents[1] / "docs" / "guide" / "budget.md"
PRESET = resources.files("satchain.presets").joinpath("ankarasat3.toml")

#: The preset's camera with its active area given as widths (80 % and 90 % of the 5.88 um pitch).
WIDTHS_DESIGN = {"detector": {"pitch_m": 5.88e-6, "active_width_x_m": 4.704e-6, "active_width_y_m": 5.292e-6}}


def _readme_system() -> str:
    """The system file of docs/guide/budget.md ("A system file"), written there by ``cat > mycamera.toml``."""
    section = BUDGET.read_text().split("### A system file", 1)[1]
    return re.search(r"^cat > mycamera\.toml <<'EOF'\n(.*?)^EOF$", section, re.S | re.M).group(1)


def _design(tmp_path: Path, system: str) -> dict:
    """A ``[system]`` table: the preset, or the guide's system file written into ``tmp_path``."""
    if system == "preset":
        return {"preset": "ankarasat3"}
    (tmp_path / "design.toml").write_text(_readme_system())
    return {"file": "design.toml"}


def _camera(system: ImagingSystem) -> dict:
    """What makes the camera: everything but its name, description and provenance."""
    return system.model_dump(exclude={"name", "description", "provenance"})


@pytest.mark.parametrize("design", ["preset", "readme"])
@pytest.mark.parametrize("built", ["preset", "readme"])
def test_a_complete_system_file_is_the_camera_as_built(tmp_path, design, built):
    (tmp_path / "readme.toml").write_text(_readme_system())
    built_file = str(PRESET) if built == "preset" else "readme.toml"
    config = {"system": _design(tmp_path, design), "as_built": {"file": built_file}}
    cfg = RunConfig.from_dict(config, base_dir=tmp_path)
    got = cfg.load_as_built_system()
    want = load_preset("ankarasat3") if built == "preset" else ImagingSystem.from_toml(tmp_path / "readme.toml")
    assert _camera(got) == _camera(want)  # the file's camera, nothing of the design's left over
    if design == built:  # as built = as designed: nothing differs, so every prediction is the design's
        assert system_differences(cfg.load_system(), got) == []
        assert got == cfg.load_system()  # the very system: the run predicts it once, as the design


def test_inline_keys_apply_over_a_complete_file(tmp_path):
    (tmp_path / "readme.toml").write_text(_readme_system())
    cfg = RunConfig.from_dict({"as_built": {"file": "readme.toml", "motion": {"smear_px": 2.5}}}, base_dir=tmp_path)
    built = cfg.load_as_built_system()
    assert built.motion.smear_px == 2.5
    assert built.optics.f_number == 9.72  # the file's, not the preset design's 7.92
    assert built.atmosphere.turbulence  # a section the design does not have


def test_a_motion_only_file_merges_over_the_design(tmp_path):
    (tmp_path / "m.toml").write_text("[motion]\nsmear_px = 2.0\n")
    built = RunConfig.from_dict({"as_built": {"file": "m.toml"}}, base_dir=tmp_path).load_as_built_system()
    diffs = system_differences(load_preset("ankarasat3"), built)
    assert [d["key"] for d in diffs] == ["motion.smear_px"]


@pytest.mark.parametrize("as_file", [False, True])
def test_fill_factor_over_a_design_with_active_widths(tmp_path, as_file):
    (tmp_path / "d.toml").write_text("[detector]\nfill_factor = 0.64\n")
    built_ref = {"file": "d.toml"} if as_file else {"detector": {"fill_factor": 0.64}}
    config = {"system": {"inline": _preset_with(WIDTHS_DESIGN)}, "as_built": built_ref}
    cfg = RunConfig.from_dict(config, base_dir=tmp_path)
    det = cfg.load_as_built_system().detector
    assert det.active_width_x_m == pytest.approx(0.8 * 5.88e-6) and det.active_width_y_m == pytest.approx(0.8 * 5.88e-6)
    assert det.fill_factor == pytest.approx(0.64)


def test_active_widths_over_a_design_with_fill_factor(tmp_path):
    (tmp_path / "d.toml").write_text("[detector]\nactive_width_x_m = 4.704e-6\nactive_width_y_m = 5.292e-6\n")
    built = RunConfig.from_dict({"as_built": {"file": "d.toml"}}, base_dir=tmp_path).load_as_built_system()
    assert (built.detector.active_width_x_m, built.detector.active_width_y_m) == (4.704e-6, 5.292e-6)
    assert built.detector.fill_factor == pytest.approx(0.72)


def test_pitch_and_fill_factor_together_in_a_partial_file(tmp_path):
    """Both shorthands at once (the guide system file's pair) raised KeyError; either order."""
    for text in ("pitch_m = 6e-6\nfill_factor = 0.81\n", "fill_factor = 0.81\npitch_m = 6e-6\n"):
        (tmp_path / "d.toml").write_text("[detector]\n" + text)
        det = RunConfig.from_dict({"as_built": {"file": "d.toml"}}, base_dir=tmp_path).load_as_built_system().detector
        assert (det.pitch_x_m, det.pitch_y_m) == (6e-6, 6e-6)
        assert det.active_width_x_m == pytest.approx(0.9 * 6e-6) and det.active_width_y_m == pytest.approx(0.9 * 6e-6)


def test_a_new_pitch_keeps_each_axis_fill_ratio():
    """``detector.pitch_m`` alone scales each active width with its pitch (a 0.8 x 0.9 active area stays so)."""
    built = ImagingSystem.from_dict(_preset_with(WIDTHS_DESIGN)).replace({"detector.pitch_m": 1.0e-5})
    assert built.detector.active_width_x_m == pytest.approx(0.8e-5)
    assert built.detector.active_width_y_m == pytest.approx(0.9e-5)
    # a pitch with active widths given with it: those widths, no fill factor left over to conflict with them
    both = ImagingSystem.from_dict(_preset_with(WIDTHS_DESIGN)).replace(
        {"detector.pitch_m": 1.0e-5, "detector.active_width_x_m": 0.5e-5}
    )
    assert (both.detector.active_width_x_m, both.detector.active_width_y_m) == (0.5e-5, pytest.approx(0.9e-5))
    assert math.isclose(both.detector.fill_factor, 0.45)


def _preset_with(sections: dict) -> dict:
    d = load_preset("ankarasat3").to_dict()
    for section, values in sections.items():
        d[section] = {k: v for k, v in d[section].items() if not k.startswith(("pitch", "active_width"))} | values
    return d
