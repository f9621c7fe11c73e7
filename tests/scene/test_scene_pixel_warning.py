"""Issue 29, item 20: a scene item whose smallest dimension spans fewer than 3 scene pixels is finer than its raster
resolves -- the raster keeps each pixel's area average, not the item's shape -- and satchain says so, with the
scene pixel an object smaller than the GSD needs (GSD/28 for 1e-3 of its image's peak)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.errors import SatchainWarning
from satchain.scene.layout import check_scene_pixel, layout_from_dict, paper_layout

LAYOUT = {
    "scene": {"width_m": 16.0, "height_m": 9.0, "background": 0.2, "pixel_m": 0.05},
    "items": [
        {"kind": "bar_target", "id": "fine_bars", "origin_m": [1.0, 1.0], "periods_m": [1.0, 0.4]},
        {"kind": "car", "id": "turned_car", "origin_m": [12.5, 4.5], "rotation_deg": 30.0},
    ],
}


def _warned(scene, pixel_m, name="pixel_m"):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ids = check_scene_pixel(scene, pixel_m, name=name)
    return ids, [str(w.message) for w in caught if issubclass(w.category, SatchainWarning)]


def test_items_finer_than_three_scene_pixels_are_named_with_the_pixel_they_need():
    scene = layout_from_dict(LAYOUT)
    ids, messages = _warned(scene, 0.1)  # the 0.2 m bars span 2 scene pixels
    assert ids == ["fine_bars"] and len(messages) == 1
    assert "pixel_m = 0.1 m: 1 scene item(s) have features narrower than 3 scene pixels" in messages[0]
    assert "fine_bars (bar_target) 0.2 m = 2 px" in messages[0]
    assert "GSD/28 for 1e-3" in messages[0]
    assert _warned(scene, 0.05) == ([], [])  # 4 scene pixels across the narrowest bar


def test_an_objects_smallest_dimension_is_taken_in_its_own_frame():
    """A car turned by 30 degrees is still 1.85 m wide (its bounding box is wider): warned of at 0.7 m, not 0.6."""
    scene = layout_from_dict(LAYOUT)
    car = next(it for it in scene.items if it.id == "turned_car")
    unturned = layout_from_dict({**LAYOUT, "items": [{**LAYOUT["items"][1], "rotation_deg": 0.0}]}).items[0]
    bbox = car.bbox_m()
    assert car.smallest_feature_m == pytest.approx(unturned.smallest_feature_m, rel=1e-9)
    assert min(bbox[2] - bbox[0], bbox[3] - bbox[1]) > 1.2 * car.smallest_feature_m
    assert "turned_car" in _warned(scene, 0.7)[0] and "turned_car" not in _warned(scene, 0.6)[0]


def test_the_paper_layout_at_its_own_pixel_is_resolved():
    scene = paper_layout()
    assert _warned(scene, scene.pixel_m) == ([], [])
    assert {"wedge_vertical", "wedge_horizontal"} <= set(_warned(scene, 0.1)[0])  # 0.125 m lines: 1.25 px


def test_simulate_prints_the_warning_once_and_still_simulates(tmp_path):
    import json

    layout = tmp_path / "fine.json"
    layout.write_text(json.dumps(LAYOUT))
    out = tmp_path / "sim.tif"
    args = ["simulate", str(layout), "--scene-pixel-m", "0.1", "--no-noise", "--units", "reflectance", "-o", str(out)]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    lines = [ln for ln in r.output.splitlines() if ln.startswith("warning: --scene-pixel-m = 0.1 m")]
    assert len(lines) == 1 and "fine_bars" in lines[0]
    assert out.exists() and np.isfinite(np.asarray(__import__("tifffile").imread(out), float)).all()


def test_a_run_names_its_scene_pixel_key(tmp_path):
    import json

    from satchain.config.run import RunConfig
    from satchain.pipeline import _stage_scene

    layout = tmp_path / "fine.json"
    layout.write_text(json.dumps(LAYOUT))
    config = RunConfig.from_dict({"scene": {"layout": str(layout), "pixel_m": 0.1}}, base_dir=tmp_path)
    with pytest.warns(SatchainWarning, match=r"scene\.pixel_m = 0\.1 m: 1 scene item\(s\) .*\(fine_bars") as w:
        _stage_scene(config, lambda *a: None)
    assert sum("scene.pixel_m" in str(x.message) for x in w) == 1  # named once, by the run's own key
