"""[as_built]: the camera as built is simulated, the design predicted; what differs is listed (issue 18)."""

from __future__ import annotations

import re
import sys

import numpy as np
import pytest

import satchain
from satchain.config.run import DEFAULT_CONFIG_TOML, RunConfig, config_to_toml, load_run_config, system_differences
from satchain.config.system import load_preset
from satchain.errors import ConfigError, SatchainIOError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

DESIGN_SMEAR_PX = load_preset("ankarasat3").motion.smear_px

#: Two edges and two wedges (ALT and ACT) on a small scene: a run takes a few seconds.
SCENE_TOML = """
[scene]
width_m = 170.0
height_m = 140.0
background = 0.2
pixel_m = 0.07

[[items]]
kind = "slanted_edge"
id = "edge_act"
center_m = [35.0, 35.0]
angle_deg = 6.0
measures = "act"

[[items]]
kind = "slanted_edge"
id = "edge_alt"
center_m = [35.0, 102.0]
angle_deg = 7.0
measures = "alt"

[[items]]
kind = "hyperbolic_wedge"
id = "wedge_h"
origin_m = [75.0, 90.0]
orientation = "horizontal"

[[items]]
kind = "hyperbolic_wedge"
id = "wedge_v"
origin_m = [100.0, 5.0]
orientation = "vertical"
"""


# ------------------------------------------------------------------------------------------- configuration


def test_as_built_merges_over_the_design_and_lists_differences():
    cfg = RunConfig.from_dict({"as_built": {"motion": {"smear_px": 3.0}, "optics": {"f_number": 10.0}}})
    design, built = cfg.load_system(), cfg.load_as_built_system()
    assert built.motion.smear_px == 3.0 and design.motion.smear_px == DESIGN_SMEAR_PX
    assert built.optics.aperture_diameter_m == design.optics.aperture_diameter_m  # only what is given changes
    assert built.optics.focal_length_m == pytest.approx(10.0 * design.optics.aperture_diameter_m)
    diffs = {d["key"]: (d["design"], d["as_built"]) for d in system_differences(design, built)}
    assert diffs["motion.smear_px"] == (DESIGN_SMEAR_PX, 3.0)
    assert diffs["optics.f_number"] == (design.optics.f_number, 10.0)
    assert set(diffs) == {"motion.smear_px", "optics.f_number", "optics.focal_length_m"}
    assert RunConfig().load_as_built_system() is None
    assert system_differences(design, design) == [] and system_differences(design, None) == []


def test_as_built_file_relative_to_the_config_and_inline_keys_over_it(tmp_path):
    (tmp_path / "built.toml").write_text("[motion]\nsmear_px = 2.0\njitter_rms_px = 0.1\n")
    (tmp_path / "run.toml").write_text('[as_built]\nfile = "built.toml"\nmotion = { smear_px = 2.5 }\n')
    cfg = load_run_config(tmp_path / "run.toml")
    built = cfg.load_as_built_system()
    assert built.motion.smear_px == 2.5 and built.motion.jitter_rms_px == 0.1
    assert cfg.as_built_path() == (tmp_path / "built.toml").resolve()
    # written into a run folder, the file is recorded absolute: the config reads back from anywhere
    text = config_to_toml(cfg)
    back = RunConfig.from_dict(tomllib.loads(text), base_dir="/")
    assert back.as_built["file"] == str((tmp_path / "built.toml").resolve())
    assert back.load_as_built_system() == built


def test_as_built_round_trips_through_toml():
    cfg = RunConfig.from_dict({"as_built": {"motion": {"smear_px": 3.0}, "optics": {"wfe_rms_waves": 0.05}}})
    assert RunConfig.from_dict(tomllib.loads(config_to_toml(cfg))) == cfg
    # the printed default configuration documents [as_built] without setting it
    default = RunConfig.from_dict(tomllib.loads(DEFAULT_CONFIG_TOML))
    assert default == RunConfig() and default.as_built is None
    assert "[as_built]" in DEFAULT_CONFIG_TOML


@pytest.mark.parametrize(
    ("as_built", "names"),
    [
        ({"motion": {"smear_pxx": 3.0}}, "as_built.motion.smear_pxx"),
        ({"motion": {"smear_px": -3.0}}, "as_built.motion.smear_px = -3.0"),
        ({"optics": {"obscuration_ratio": 1.2}}, "as_built.optics.obscuration_ratio = 1.2"),
        ({"motions": {"smear_px": 3.0}}, "as_built.motions"),
        ({"motion": 3.0}, "as_built.motion = 3.0"),
        ({"file": 5}, "as_built.file = 5"),
    ],
)
def test_bad_as_built_is_refused_naming_the_key(as_built, names):
    with pytest.raises(ConfigError) as exc:
        RunConfig.from_dict({"as_built": as_built}).load_as_built_system()
    msg = str(exc.value)
    assert names in msg and "\n" not in msg


def test_missing_as_built_file_is_refused(tmp_path):
    cfg = RunConfig.from_dict({"as_built": {"file": "nosuch.toml"}}, base_dir=tmp_path)
    with pytest.raises(SatchainIOError, match="as_built.file"):
        cfg.load_as_built_system()


# ------------------------------------------------------------------------------------------------ end to end


def _run(tmp_path_factory, name: str, extra: dict):
    d = tmp_path_factory.mktemp(name)
    (d / "scene.toml").write_text(SCENE_TOML)
    return satchain.run(RunConfig.from_dict({"scene": {"layout": "scene.toml", "pixel_m": 0.07}, **extra}, base_dir=d))


@pytest.fixture(scope="module")
def design_run(tmp_path_factory):
    return _run(tmp_path_factory, "design", {})


@pytest.fixture(scope="module")
def as_built_run(tmp_path_factory):
    return _run(tmp_path_factory, "asbuilt", {"as_built": {"motion": {"smear_px": 3.0}}})


def _rows(result):
    return {(r.kind, r.id): r for r in result.comparison.rows}


def test_without_as_built_everything_passes(design_run):
    assert design_run.passed is True
    assert all(r.passed for r in design_run.comparison.rows)
    assert design_run.to_json_dict()["as_built_differences"] == []
    assert design_run.simulation.system == design_run.system


def test_as_built_smear_fails_the_alt_checks(design_run, as_built_run):
    """Smear 3 px built, 1.03 px designed: the ALT edge and the ALT (horizontal) wedge fail; the ACT ones pass;
    the predictions are the design's, unchanged."""
    r = as_built_run
    assert r.passed is False
    rows = _rows(r)
    assert rows[("edge_mtf_at_nyquist", "edge_alt")].passed is False
    assert rows[("wedge_resolution", "wedge_h")].passed is False
    assert rows[("wedge_resolution", "wedge_h")].measured > 1.5 * rows[("wedge_resolution", "wedge_h")].predicted
    assert rows[("edge_mtf_at_nyquist", "edge_act")].passed is True
    assert rows[("wedge_resolution", "wedge_v")].passed is True
    for key, row in _rows(design_run).items():  # predicted from [system] in both runs
        assert rows[key].predicted == row.predicted
    assert r.system.motion.smear_px == DESIGN_SMEAR_PX and r.simulation.system.motion.smear_px == 3.0
    res = r.to_json_dict()
    assert res["as_built_differences"] == [{"key": "motion.smear_px", "design": DESIGN_SMEAR_PX, "as_built": 3.0}]
    assert res["pass"] is False


def test_predicted_and_measured_wedge_contrast_agree(design_run):
    """The predicted scan (noise-free predicted image) and the measured one agree within 0.03 where the lines
    are wider than 2 GSD; every wedge row has a sigma."""
    for w in design_run.comparison.hyperbolic_wedge:
        lw = np.asarray(w.line_width_m, float)
        wide = lw > 2 * w.gsd_m
        assert wide.sum() >= 3
        diff = np.asarray(w.contrast, float)[wide] - np.asarray(w.contrast_predicted, float)[wide]
        assert np.max(np.abs(diff)) < 0.03, w.id
    for row in design_run.comparison.rows:
        if row.kind == "wedge_resolution":
            assert row.sigma is not None and 0 < row.sigma < 0.5


def test_design_with_more_smear_predicts_it(tmp_path_factory):
    """A design with smear 3 px simulated as designed: the ALT wedge prediction is the modelled ~0.9-1 m (not the
    0.49 m GSD a clamped prediction gave) and the check passes."""
    design = load_preset("ankarasat3").replace({"motion.smear_px": 3.0}).to_dict()
    r = _run(tmp_path_factory, "smear3", {"system": {"inline": design}})
    row = _rows(r)[("wedge_resolution", "wedge_h")]
    assert 0.8 < row.predicted < 1.15
    assert row.passed is True


def test_report_lists_what_differs(design_run, as_built_run, tmp_path):
    from satchain.pipeline import ReportInputs
    from satchain.report import html

    for name, result in (("built", as_built_run), ("design", design_run)):
        (tmp_path / name).mkdir()
        html.write_report(ReportInputs(result, tmp_path / name, result.to_json_dict()), tmp_path / name / "r.html")
    built = (tmp_path / "built" / "r.html").read_text()
    block = built[built.index('id="as-built"') : built.index("</div>", built.index('id="as-built"'))]
    assert "motion.smear_px" in block and f"<td>{DESIGN_SMEAR_PX}</td><td>3.0</td>" in block
    assert 'id="as-built"' not in (tmp_path / "design" / "r.html").read_text()


def test_as_built_at_another_altitude_draws_the_image_at_its_own_gsd(tmp_path_factory):
    """Built to fly 8 % higher (or the focal length off): the image's pixels are the as-built GSD, and the
    report's thumbnails, overlays and edge curves place the targets with it, not with the design's GSD."""
    from satchain.pipeline import ReportInputs
    from satchain.report.kinds import overlay_svg

    design = load_preset("ankarasat3")
    r = _run(tmp_path_factory, "higher", {"as_built": {"orbit": {"altitude_m": 1.08 * design.orbit.altitude_m}}})
    view = ReportInputs(r, tmp_path_factory.mktemp("view"), r.to_json_dict())
    assert view.image_gsd_m == pytest.approx(1.08 * design.gsd_act_m, rel=1e-9)
    assert view.image_gsd_m == r.simulation.system.gsd_act_m != view.system.gsd_act_m
    # the image covers the scene at the as-built pixel: its width x the as-built GSD is the scene's width
    assert r.simulation.image.shape[1] * view.image_gsd_m == pytest.approx(170.0, abs=2 * view.image_gsd_m)
    # an edge's fit line is drawn where the edge is (scene metres), whatever the pixel
    truth = {it["id"]: it for it in r.scene.truth_dict["items"]}
    edge = next(e for e in r.measurements.to_dict()["slanted_edges"] if e["id"] == "edge_act")
    box = truth["edge_act"]["bbox_m"]

    def roi_centre(gsd):
        svg = overlay_svg(truth["edge_act"], edge, box, gsd_m=gsd, display_px=200.0)
        x, y, w, h = (float(re.search(f' {k}="([-0-9.]+)"', svg.split("<rect")[1]).group(1))
                      for k in ("x", "y", "width", "height"))  # fmt: skip
        ex, ey = truth["edge_act"]["edge_point_m"]
        return np.hypot(x + w / 2 - ex, y + h / 2 - ey)

    assert roi_centre(view.image_gsd_m) < 1.0  # the measured region drawn around the edge
    assert roi_centre(view.system.gsd_act_m) > 2.0  # (the design's GSD would draw it 8 % off, metres away)
