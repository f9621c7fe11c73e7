"""Issue 21, point 3: the thumbnails' ground truth kept as the simulation renders the scene is, pixel for pixel,
the panel the report renders itself; a panel not wholly rendered, or too large to keep, is left to the report."""

import numpy as np
import pytest

from satchain.report.gallery import grey8_truth_panel, panel_window, to_grey8, truth_panel
from satchain.report.truth_crops import TruthCrops
from satchain.scene import load_layout

P = 0.07
SCENE = """
[scene]
width_m = 40.0
height_m = 30.0
background = 0.2
pixel_m = 0.07

[[items]]
kind = "siemens_star"
id = "star"
center_m = [12.0, 14.0]
radius_m = 9.0
cycles = 24

[[items]]
kind = "slanted_edge"
id = "edge"
center_m = [31.0, 15.0]
angle_deg = 6.0
size_m = 12.0
measures = "act"
"""
STAR_BOX, EDGE_BOX = (2.5, 4.5, 21.5, 23.5), (24.0, 8.0, 38.0, 22.0)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "scene.toml"
    path.write_text(SCENE)
    return load_layout(path)


def _read_in_tiles(view, shape, tile, overlap):
    """Render the whole scene through ``view`` in overlapping tiles, as the engine reads it."""
    rows, cols = shape
    for r in range(0, rows, tile[0]):
        for c in range(0, cols, tile[1]):
            r0, c0 = max(r - overlap, 0), max(c - overlap, 0)
            h, w = min(r + tile[0] + overlap, rows) - r0, min(c + tile[1] + overlap, cols) - c0
            got = view.render((r0, c0, h, w), pixel_m=P)
            assert got.shape == (h, w)


@pytest.mark.parametrize("tile, overlap", [((97, 131), 0), ((64, 200), 13), ((430, 580), 0)])
def test_kept_panels_are_the_reports_own_render(scene, tile, overlap):
    view = TruthCrops(scene, [STAR_BOX, EDGE_BOX], P)
    assert view.shape_px(P) == scene.shape_px(P)  # every other attribute is the scene's
    _read_in_tiles(view, scene.shape_px(P), tile, overlap)
    for box in (STAR_BOX, EDGE_BOX):
        grey = view.take(box)
        own = scene.render(panel_window(box, P), pixel_m=P)
        np.testing.assert_array_equal(grey, to_grey8(own))
        assert grey8_truth_panel(grey, P) == truth_panel(scene, box, P)


def test_render_passes_the_scene_through_unchanged(scene):
    view = TruthCrops(scene, [STAR_BOX], P)
    win = (40, 30, 120, 150)
    np.testing.assert_array_equal(view.render(win, pixel_m=P), scene.render(win, pixel_m=P))
    np.testing.assert_array_equal(view.render(win, pixel_m=2 * P), scene.render(win, pixel_m=2 * P))


def test_a_panel_not_wholly_rendered_is_left_to_the_report(scene):
    view = TruthCrops(scene, [STAR_BOX], P)
    r0, c0, h, w = panel_window(STAR_BOX, P)
    view.render((r0, c0, h - 1, w), pixel_m=P)  # its last row never rendered
    assert view.take(STAR_BOX) is None
    view.render((r0 + h - 1, c0, 1, w), pixel_m=2 * P)  # at another pixel size: not kept
    assert view.take(STAR_BOX) is None
    view.render((r0 + h - 1, c0, 1, w), pixel_m=P)
    assert view.take(STAR_BOX) is not None
    assert view.take(EDGE_BOX) is None  # never asked to keep
    view.release()
    assert view.take(STAR_BOX) is None


def test_a_panel_too_large_to_keep_is_left_to_the_report(scene, monkeypatch):
    import satchain.report.truth_crops as tc

    monkeypatch.setattr(tc, "MAX_SIDE_PX", 200)  # the star's panel (270 px) would be block-averaged
    view = tc.TruthCrops(scene, [STAR_BOX, EDGE_BOX], P)
    _read_in_tiles(view, scene.shape_px(P), (200, 200), 0)
    assert view.take(STAR_BOX) is None and view.take(EDGE_BOX) is not None
    monkeypatch.setattr(tc, "MAX_SIDE_PX", 2000)
    monkeypatch.setattr(tc, "MAX_KEPT_PX", 80_000)  # room for the first window only
    view = tc.TruthCrops(scene, [STAR_BOX, EDGE_BOX], P)
    _read_in_tiles(view, scene.shape_px(P), (200, 200), 0)
    assert view.take(STAR_BOX) is not None and view.take(EDGE_BOX) is None
