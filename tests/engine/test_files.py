"""satchain.engine.files.simulate_file: what `satchain simulate` does, as a tested library function."""

from __future__ import annotations

import numpy as np
import pytest
from _reference import make_scene

from satchain import io, load_preset
from satchain.engine import georaster
from satchain.engine.files import SimulatedFile, simulate_file
from satchain.engine.simulate import simulate
from satchain.errors import ConfigError, SatchainError

SYSTEM = load_preset("ankarasat3")
PIXEL_M = 0.245  # 2 input pixels per GSD (0.49 m)


@pytest.fixture()
def scene_tif(tmp_path):
    img = make_scene((120, 96), np.random.default_rng(5), rectangles=4).astype(np.float32)
    path = tmp_path / "in.tif"
    io.write_tiff(path, img, pixel_m=PIXEL_M)
    return path, img


def test_a_uniform_field_stays_uniform_at_the_output_pixel_size(tmp_path):
    # the OTF is 1 at zero frequency and the detector averages: a flat reflectance of 0.3 comes out 0.3
    path = tmp_path / "flat.tif"
    io.write_tiff(path, np.full((80, 64), 0.3, dtype=np.float32), pixel_m=PIXEL_M)
    r = simulate_file(path, tmp_path / "o" / "sim.tif", SYSTEM, units="reflectance", noise=False)
    img, meta = io.read_image(r.path)
    assert r.shape_px == img.shape == (int(80 * PIXEL_M / 0.49 + 1e-9), int(64 * PIXEL_M / 0.49 + 1e-9))
    np.testing.assert_allclose(img, 0.3, atol=1e-6)
    assert meta["pixel_m"] == pytest.approx(SYSTEM.gsd_act_m)
    assert r.preview.is_file() and r.preview == tmp_path / "o" / "sim.png"


def test_the_file_is_the_in_memory_simulation_and_the_focal_plane_comes_on_request(tmp_path, scene_tif):
    path, img = scene_tif
    fp = tmp_path / "fp" / "focal.tif"
    r = simulate_file(path, tmp_path / "sim.tif", SYSTEM, units="reflectance", noise=False, focal_plane=fp)
    assert isinstance(r, SimulatedFile) and not r.streamed and r.units == "reflectance"
    on_disk, _ = io.read_image(r.path)
    expected = simulate(img.astype(float), SYSTEM, pixel_m=PIXEL_M)
    np.testing.assert_allclose(on_disk, expected, atol=1e-6)
    f, meta = io.read_image(fp)
    assert r.focal_plane_path == fp and f.shape == img.shape  # on the input grid
    assert r.focal_plane_pixel_m == pytest.approx(PIXEL_M) and meta["pixel_m"] == pytest.approx(PIXEL_M)
    assert abs(float(f.mean()) - float(img.mean())) < 0.01  # filtered, not rescaled
    coarse = simulate_file(path, tmp_path / "c.tif", SYSTEM, units="reflectance", noise=False,
                           focal_plane=tmp_path / "fc.tif", focal_plane_grid="coarse")  # fmt: skip
    fc, _ = io.read_image(tmp_path / "fc.tif")
    d = round(coarse.focal_plane_pixel_m / PIXEL_M)
    assert d >= 1 and fc.shape == (-(-img.shape[0] // d), -(-img.shape[1] // d))


def test_noise_follows_the_seed_and_dn_are_integers_in_the_adc_range(tmp_path, scene_tif):
    path, _ = scene_tif
    runs = (("a", 7), ("b", 7), ("c", 8))
    a, b, c = (simulate_file(path, tmp_path / f"{n}.tif", SYSTEM, seed=s).path for n, s in runs)
    da, db, dc = (io.read_image(p)[0] for p in (a, b, c))
    np.testing.assert_array_equal(da, db)
    assert not np.array_equal(da, dc)
    assert da.dtype == np.uint16 and int(da.max()) < 2**SYSTEM.detector.bit_depth


def test_the_streamed_path_writes_the_same_image_and_says_so(tmp_path, scene_tif, monkeypatch):
    path, _ = scene_tif
    full = simulate_file(path, tmp_path / "full.tif", SYSTEM, units="reflectance", noise=False)
    monkeypatch.setattr(georaster, "_in_memory", lambda *a, **k: False)
    said, stages = [], []
    r = simulate_file(path, tmp_path / "s.tif", SYSTEM, units="reflectance", noise=False, notify=said.append,
                      progress=lambda stage, done, total: stages.append((stage, done, total)))  # fmt: skip
    assert r.streamed and r.shape_px == full.shape_px and r.focal_plane_path is None
    assert len(said) == 1 and said[0].startswith("streamed:")
    assert {s for s, _, _ in stages} == {s for s, _, _ in stages if s.startswith(("stage 1", "stage 2"))}
    assert stages[-1][0].startswith("stage 2") and stages[-1][1] == stages[-1][2]
    np.testing.assert_allclose(io.read_image(r.path)[0], io.read_image(full.path)[0], atol=1e-6)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no scratch folder left


def test_progress_reports_one_stage_to_completion(tmp_path, scene_tif):
    path, _ = scene_tif
    seen = []
    simulate_file(path, tmp_path / "p.tif", SYSTEM, progress=lambda s, d, t: seen.append((s, d, t)))
    assert {s for s, _, _ in seen} == {"simulating 120x96 px"}
    assert seen[-1][1] == seen[-1][2] > 0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"units": "kelvin"}, "units = 'kelvin'"),
        ({"seed": -1}, "seed -1: must be an integer >= 0"),
        ({"seed": True}, "seed True"),
        ({"noise": "yes"}, "noise = 'yes'"),
        ({"focal_plane_grid": "fine"}, "focal_plane_grid = 'fine'"),
    ],
)
def test_bad_options_are_refused_before_anything_is_written(tmp_path, scene_tif, kwargs, message):
    path, _ = scene_tif
    with pytest.raises(SatchainError, match=message.replace("(", r"\(")):
        simulate_file(path, tmp_path / "x.tif", SYSTEM, **kwargs)
    assert not (tmp_path / "x.tif").exists() and not (tmp_path / "x.png").exists()


def test_a_ground_truth_under_8_px_a_side_is_refused(tmp_path):
    path = tmp_path / "tiny.tif"
    io.write_tiff(path, np.full((6, 40), 0.5, dtype=np.float32), pixel_m=PIXEL_M)
    with pytest.raises(ConfigError, match="only 6 x 40 px; a ground truth needs at least 8 px a side: check --sc"):
        simulate_file(path, tmp_path / "x.tif", SYSTEM, names={"scene_pixel_m": "--scene-pixel-m"})
    assert not (tmp_path / "x.tif").exists()


def test_outputs_never_replace_the_input_and_errors_use_the_callers_names(tmp_path, scene_tif):
    path, _ = scene_tif
    before = path.read_bytes()
    with pytest.raises(ConfigError, match="out"):
        simulate_file(path, path, SYSTEM)
    with pytest.raises(ConfigError, match=r"-o .*INPUT|INPUT.*-o"):
        simulate_file(path, path, SYSTEM, names={"out": "-o", "input": "INPUT"})
    with pytest.raises(ConfigError, match="--input-scale 0.5: applies to image inputs only"):
        simulate_file("paper", tmp_path / "y.tif", SYSTEM, input_scale=0.5, names={"input_scale": "--input-scale"})
    with pytest.raises(ConfigError, match="is a directory"):
        simulate_file(path, tmp_path, SYSTEM)
    user_png = tmp_path / "mine.png"
    user_png.write_bytes(b"not satchain's")
    with pytest.raises(ConfigError, match="not written by satchain"):
        simulate_file(path, tmp_path / "mine.tif", SYSTEM)
    assert path.read_bytes() == before and user_png.read_bytes() == b"not satchain's"
    assert not (tmp_path / "mine.tif").exists()
