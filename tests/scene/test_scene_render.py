"""render_scene_to_file: streamed TIFF == in-memory render, preview, truth, atomicity; ImageScene."""

from __future__ import annotations

import json

import numpy as np
import pytest
import tifffile

from satchain.errors import ConfigError, InputError
from satchain.io.images import read_image, write_png, write_tiff
from satchain.scene import ImageScene, paper_layout, parse_cli_window, render_scene_to_file


def test_render_to_files_matches_render(tmp_path):
    scene = paper_layout()
    window = (400, 100, 300, 530)  # rows 40-70 m, cols 10-63 m at 0.1 m: the ALT edge
    calls = []
    out = render_scene_to_file(scene, tmp_path / "o.tif", pixel_m=0.1, window=window, tile_px=64,
                               preview_max_px=100, progress=lambda d, t: calls.append((d, t)))  # fmt: skip
    image, meta = read_image(out["tiff"])
    np.testing.assert_array_equal(image, scene.render(window, pixel_m=0.1))
    assert meta["pixel_m"] == 0.1 and meta["origin_m"] == pytest.approx([10.0, 40.0])
    with tifffile.TiffFile(out["tiff"]) as tf:
        page = tf.pages[0]
        assert page.is_tiled and (page.tilelength, page.tilewidth) == (64, 64)
        assert tuple(page.tags[33550].value) == (0.1, 0.1, 0.0)
    assert calls[-1] == (300 * 530, 300 * 530)
    preview, pmeta = read_image(out["png"])
    f = pmeta["downsample"]
    assert f == 6 and preview.shape == (50, 89)
    block = scene.render(window, pixel_m=0.1)[:6, :6].astype(float).mean()
    assert abs(preview[0, 0] - round(block * 255)) <= 1
    truth = json.loads(out["truth"].read_text())
    assert truth["window_px"] == list(window) and truth["files"]["tiff"] == "o.tif"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o.png", "o.tif", "o.truth.json"]


def test_failed_render_leaves_no_file(tmp_path):
    def boom(done, total):
        raise RuntimeError("stop")

    with pytest.raises(RuntimeError, match="stop"):
        render_scene_to_file("paper", tmp_path / "x.tif", pixel_m=1.0, tile_px=16, progress=boom)
    assert list(tmp_path.iterdir()) == []


def test_parse_cli_window():
    assert parse_cli_window("10,20,30,40") == (20, 10, 40, 30)
    for bad in ("1,2,3", "a,b,c,d", "0,0,0,5"):
        with pytest.raises(ConfigError, match="window"):
            parse_cli_window(bad)


def test_image_scene_from_array_and_files(tmp_path):
    rng = np.random.default_rng(0)
    a = rng.random((20, 30)).astype(np.float32)
    s = ImageScene(a, pixel_m=0.25)
    assert s.extent_m == (7.5, 5.0) and s.shape_px() == (20, 30) and s.shape_px(0.25) == (20, 30)
    np.testing.assert_array_equal(s.render((3, 4, 5, 6), pixel_m=0.25), a[3:8, 4:10])
    write_tiff(tmp_path / "a.tif", a, pixel_m=0.3)
    t = ImageScene(tmp_path / "a.tif")
    assert t.pixel_m == 0.3
    np.testing.assert_array_equal(t.render(), a)
    u8 = (a * 255).astype(np.uint8)
    write_png(tmp_path / "a.png", u8, pixel_m=0.5)
    s8 = ImageScene(tmp_path / "a.png", scale=1 / 255)
    assert s8.pixel_m == 0.5
    np.testing.assert_allclose(s8.render(), u8 / 255, atol=1e-7)


def test_image_scene_errors(tmp_path):
    s = ImageScene(np.zeros((10, 10)), pixel_m=0.5)
    with pytest.raises(ConfigError, match="native pixel size"):
        s.render((0, 0, 2, 2), pixel_m=0.25)
    with pytest.raises(InputError, match="outside"):
        s.render((5, 5, 6, 2))
    np.save(tmp_path / "a.npy", np.zeros((4, 4)))
    with pytest.raises(ConfigError, match="pixel_m"):
        ImageScene(tmp_path / "a.npy")
    with pytest.raises(InputError, match="2-D"):
        ImageScene(np.zeros((2, 2, 3)), pixel_m=1.0)
    with pytest.raises(InputError, match="NaN"):
        ImageScene(np.full((2, 2), np.nan), pixel_m=1.0)
