"""Scenes: window == crop, culling, truth schema, scene files, the paper layout."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain.errors import ConfigError, SatchainIOError
from satchain.scene import ITEM_KINDS, Scene, layout_from_dict, layout_to_dict, load_layout, paper_layout
from satchain.scene.targets import SlantedEdge

P_COARSE = 0.5


@pytest.fixture(scope="module")
def paper():
    return paper_layout()


@pytest.fixture(scope="module")
def paper_full(paper):
    return paper.render(pixel_m=P_COARSE)


@settings(max_examples=25, deadline=None)
@given(r0=st.integers(-20, 600), c0=st.integers(-20, 400), h=st.integers(1, 90), w=st.integers(1, 90))
def test_window_equals_crop_of_full_render(paper, paper_full, r0, c0, h, w):
    win = paper.render((r0, c0, h, w), pixel_m=P_COARSE)
    padded = np.full((paper_full.shape[0] + 200, paper_full.shape[1] + 200), np.float32(paper.background))
    padded[20 : 20 + paper_full.shape[0], 20 : 20 + paper_full.shape[1]] = paper_full
    crop = padded[r0 + 20 : r0 + 20 + h, c0 + 20 : c0 + 20 + w]
    np.testing.assert_allclose(win, crop, atol=1e-6, rtol=0)


def test_window_equals_crop_fine_pixels(paper):
    """Star, wedge and objects at 0.1 m: one 400 x 500 render against tiles of it."""
    p = 0.1
    base = (100, 700, 400, 500)  # star and vertical wedge
    full = paper.render(base, pixel_m=p)
    for r, c, h, w in [(0, 0, 37, 53), (123, 250, 64, 200), (350, 451, 50, 49), (7, 399, 393, 101)]:
        tile = paper.render((base[0] + r, base[1] + c, h, w), pixel_m=p)
        np.testing.assert_allclose(tile, full[r : r + h, c : c + w], atol=1e-6, rtol=0)


def test_large_window_painted_in_bands_on_threads_equals_one_band(paper, monkeypatch):
    """A window above PARALLEL_RENDER_PX is painted in row bands on threads: bit-identical to painting it
    whole (every pixel is its own area average), across the star, wedges, bars and objects."""
    from satchain.scene import layout

    monkeypatch.setattr(layout, "_render_threads", lambda: 2)
    window = (-3, 95, 1311, 1207)  # 0.2 m pixels: most of the paper scene, past its top edge
    monkeypatch.setattr(layout, "PARALLEL_RENDER_PX", 1 << 40)
    assert len(layout._row_bands(window[2], window[3])) == 2
    whole = paper.render(window, pixel_m=0.2)
    monkeypatch.setattr(layout, "PARALLEL_RENDER_PX", 1)
    cuts = layout._row_bands(window[2], window[3])
    assert len(cuts) == 9 and cuts[0] == 0 and cuts[-1] == window[2]
    banded = paper.render(window, pixel_m=0.2)
    assert banded.dtype == np.float32 and np.array_equal(banded, whole)


def test_render_outside_items_is_background(paper):
    img = paper.render((-50, -50, 10, 10), pixel_m=0.1)
    assert np.all(img == np.float32(paper.background))


def test_paper_layout_has_every_kind_and_fits(paper):
    kinds = {it.kind for it in paper.items}
    assert kinds == set(ITEM_KINDS)
    for it in paper.items:
        x0, y0, x1, y1 = it.bbox_m()
        assert 0 <= x0 and x1 <= paper.width_m and 0 <= y0 and y1 <= paper.height_m, it.id
    assert paper.shape_px(0.035) == (8572, 5715)
    # the paper's three slanted edges, in its order (5 deg ACT, 5 deg ALT below, 10 deg ACT)
    edges = [it for it in paper.items if it.kind == "slanted_edge"]
    assert [(e.measures, e.angle_deg) for e in edges] == [("act", 5.0), ("alt", 5.0), ("act", 10.0)]
    assert edges[0].center_m[1] < edges[1].center_m[1] < edges[2].center_m[1]


def test_truth_schema(paper):
    t = json.loads(json.dumps(paper.truth(0.035, window=(0, 0, 2000, 2000))))
    assert t["format"] == "satchain-scene-truth/1"
    assert t["pixel_m"] == 0.035 and t["extent_m"] == [200.0, 300.0] and t["window_px"] == [0, 0, 2000, 2000]
    assert {"origin", "x", "y", "pixel"} <= set(t["conventions"])
    ids = [i["id"] for i in t["items"]]
    assert len(ids) == len(set(ids))
    required = {
        "slanted_edge": {"angle_deg", "edge_point_m", "normal_to_bright", "bright", "dark", "measures"},
        "bar_target": {"periods_m", "n_bars", "orientation", "groups"},
        "hyperbolic_wedge": {"orientation", "line_width_function", "boundary_A_m2", "x0_m", "n_stripes"},
        "siemens_star": {"center_m", "radius_m", "cycles"},
    }
    for item in t["items"]:
        assert item["kind"] in ITEM_KINDS
        assert {"id", "bbox_m", "bbox_px", "in_window"} <= set(item)
        assert required.get(item["kind"], set()) <= set(item)
        x0, y0, x1, y1 = item["bbox_m"]
        r0, c0, h, w = item["bbox_px"]
        assert r0 * 0.035 <= y0 + 1e-9 and (r0 + h) * 0.035 >= y1 - 1e-9
        assert c0 * 0.035 <= x0 + 1e-9 and (c0 + w) * 0.035 >= x1 - 1e-9
    star = next(i for i in t["items"] if i["kind"] == "siemens_star")
    assert star["in_window"] is False  # x >= 97 m is beyond column 2000 (70 m)


def test_layout_file_round_trip_json_and_toml(tmp_path, paper):
    d = layout_to_dict(paper)
    (tmp_path / "s.json").write_text(json.dumps(d))
    again = load_layout(tmp_path / "s.json")
    window = (1500, 1500, 64, 96)
    np.testing.assert_array_equal(again.render(window, pixel_m=0.05), paper.render(window, pixel_m=0.05))
    toml = """
[scene]
width_m = 40.0
height_m = 30.0
background = 0.3

[[items]]
kind = "slanted_edge"
id = "e"
center_m = [20.0, 15.0]
size_m = 20.0
angle_deg = 5.0

[[items]]
kind = "bar_target"
id = "b"
origin_m = [1.0, 1.0]
periods_m = [2.0, 1.0]
"""
    (tmp_path / "s.toml").write_text(toml)
    s = load_layout(tmp_path / "s.toml")
    assert [it.kind for it in s.items] == ["slanted_edge", "bar_target"]
    assert s.items[1].periods_m == (2.0, 1.0)
    assert s.render(pixel_m=1.0)[0, 39] == pytest.approx(0.3)


@pytest.mark.parametrize(
    "d, match",
    [
        ({"scene": {"width_m": 10}}, "height_m"),
        ({"scene": {"width_m": 10, "height_m": 10, "colour": 1}}, "colour"),
        ({"scene": {"width_m": 10, "height_m": 10}, "items": [{"kind": "tree", "id": "t"}]}, "kind"),
        (
            {"scene": {"width_m": 10, "height_m": 10}, "items": [{"kind": "house", "id": "h", "roof": 1}]},
            "roof",
        ),
        ({"scene": {"width_m": 10, "height_m": 10}, "items": [{"kind": "house"}]}, "id"),
        (
            {"scene": {"width_m": 10, "height_m": 10}, "items": [{"kind": "house", "id": "a"}] * 2},
            "duplicate",
        ),
        ({"scene": {"width_m": 10, "height_m": 10, "background": 2.0}}, "background"),
        ({"scene": {"width_m": -10, "height_m": 10}}, "width_m"),
        ({"items": []}, "scene"),
    ],
)
def test_bad_layouts(d, match):
    with pytest.raises(ConfigError, match=match):
        layout_from_dict(d)


def test_bad_layout_sources(tmp_path):
    with pytest.raises(SatchainIOError, match="no such file"):
        load_layout(tmp_path / "missing.toml")
    (tmp_path / "bad.toml").write_text("[scene\nwidth_m = ")
    with pytest.raises(ConfigError, match="cannot parse"):
        load_layout(tmp_path / "bad.toml")
    (tmp_path / "s.yaml").write_text("scene: {}")
    with pytest.raises(ConfigError, match=".toml or .json"):
        load_layout(tmp_path / "s.yaml")


def test_scene_render_bad_pixel():
    s = Scene(10.0, 10.0, (SlantedEdge("e", center_m=(5, 5), size_m=4),))
    with pytest.raises(ConfigError, match="pixel_m"):
        s.render(pixel_m=-1.0)
