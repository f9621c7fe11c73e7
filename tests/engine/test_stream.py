"""The streamed path (coarse grid on disk, stage 2 tile by tile, image written band by band) against the
full-frame path it replaces for inputs too large for memory."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from _reference import make_scene
from typer.testing import CliRunner

from satchain import load_preset
from satchain.engine.memory import simulation_bytes
from satchain.engine.sensor import sensor_from_system
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import ArraySource
from satchain.engine.stream import choose_streamed, coarse_store, stream_bytes, stream_tile_px, stream_tiles

BASE = load_preset("ankarasat3")
PIXEL_M = 0.035
GiB = 2**30


def _assemble(sim, coarse, **kw) -> np.ndarray:
    out = np.full(sim.output_shape, np.nan)
    for r0, c0, t in stream_tiles(sim, coarse, **kw):
        out[r0 : r0 + t.shape[0], c0 : c0 + t.shape[1]] = t
    return out


@pytest.fixture(scope="module")
def case():
    """A 1568 x 1540 scene of noise and rectangles (every frequency, sharp edges), its coarse grid (on disk)
    and the full-frame image."""
    img = make_scene((1568, 1540), np.random.default_rng(11), rectangles=12)
    src = ArraySource(img, pixel_m=PIXEL_M)
    full_sim = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=img.shape)
    with coarse_store(full_sim) as coarse:
        full_sim.decimate(src, out=coarse)
        yield src, np.array(coarse), full_sim.form_image(coarse)


@pytest.mark.parametrize("border", ["symmetric", "constant"])
def test_streamed_equals_full_frame_within_the_stated_bound(case, border):
    src, _, _ = case
    full_sim = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=src.shape_px, params=SimParams(border=border))
    coarse = full_sim.decimate(src)
    full = full_sim.form_image(coarse)
    errors = {}
    for margin in (16, 64):
        p = SimParams(border=border, stream_tile_px=64, stream_margin_px=margin)
        sim = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=src.shape_px, params=p)
        _, window = sim.tile_window((0, 64), (0, 64), margin)
        assert all(w < f for w, f in zip(window, sim.frame_shape, strict=True))  # a real window, not the frame
        for far in (None, False):
            errors[margin, far] = np.max(np.abs(_assemble(sim, coarse, far=far) - full)) / np.ptp(full)
    assert errors[64, None] <= 1e-5 and errors[16, None] <= 1e-4  # the whole frame's far field: short margins
    assert errors[64, False] > 10 * errors[64, None]  # without it the PSF tail wraps around each window
    assert errors[16, False] > 2 * errors[64, False]  # ... and the margin sets the error


@pytest.mark.parametrize(("pixel_m", "phase"), [(0.04, (0.0, 0.0)), (0.035, (3.3, 1.7))])
def test_streamed_any_ratio_and_phase(pixel_m, phase):
    """A non-integer GSD / input ratio (matrix DFT in every window) and a sub-pixel detector phase."""
    img = make_scene((2100, 1900), np.random.default_rng(2))
    sim = Simulator(BASE, input_pixel_m=pixel_m, input_shape=img.shape, params=SimParams(phase_px=phase))
    coarse = sim.decimate(ArraySource(img, pixel_m=pixel_m))
    full = sim.form_image(coarse)
    p = SimParams(phase_px=phase, stream_tile_px=64, stream_margin_px=64)
    streamed = Simulator(BASE, input_pixel_m=pixel_m, input_shape=img.shape, params=p)
    assert np.max(np.abs(_assemble(streamed, coarse) - full)) <= 1e-5 * np.ptp(full)


def test_streamed_periodic_border_wraps_like_the_full_frame(case):
    """Under the periodic rule the frame is the coarse grid itself (no extension): windows wrap around it."""
    src, _, _ = case
    p = SimParams(border="periodic", stream_tile_px=64, stream_margin_px=16)
    sim = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=src.shape_px, params=p)
    coarse = sim.decimate(src)
    full = sim.form_image(coarse)
    _, window = sim.tile_window((0, 64), (0, 64), 16)
    assert all(w < f for w, f in zip(window, sim.frame_shape, strict=True))
    assert np.max(np.abs(_assemble(sim, coarse) - full)) <= 1e-4 * np.ptp(full)


def test_streamed_noise_is_the_full_frame_noise(case):
    """The sensor runs per tile on the fixed noise-block grid: the streamed DN equal the sensor applied to
    the assembled image in one piece (bit for bit), and the full-frame DN wherever the optics agree."""
    src, coarse, full = case
    sensor = sensor_from_system(BASE)
    p = SimParams(stream_tile_px=64, stream_margin_px=32)
    sim = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=src.shape_px, params=p)
    clean = _assemble(sim, coarse)
    noisy = _assemble(sim, coarse, sensor=sensor, units="dn", noise=True, seed=7)
    whole = sensor.convert(clean, origin=(0, 0), units="dn", noise=True, seed=7)
    np.testing.assert_array_equal(noisy, whole)
    full_noisy = sensor.convert(full, origin=(0, 0), units="dn", noise=True, seed=7)
    # the optics differ by ~1e-5 of the range (~0.03 DN): a DN or a Poisson quantile flips by one at a few pixels
    assert np.max(np.abs(noisy - full_noisy)) <= 1 and np.mean(noisy != full_noisy) < 0.01
    expect = sensor.convert(full, origin=(0, 0), units="dn", noise=False)
    assert np.corrcoef((noisy - expect).ravel(), (full_noisy - expect).ravel())[0, 1] > 0.99  # the same draws
    other = _assemble(sim, coarse, sensor=sensor, units="dn", noise=True, seed=8)
    assert np.mean(other != noisy) > 0.5  # the seed matters


def test_huge_input_streams_and_is_planned_without_allocating():
    tracemalloc.start()
    sim = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=(100_000, 100_000))
    streamed = choose_streamed(sim, limit_bytes=8 * GiB)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert streamed and peak < 64 * 2**20
    assert simulation_bytes(sim) > 8 * GiB and sim.frame_bytes > sim.params.max_frame_bytes
    assert stream_bytes(sim) < 4 * GiB
    assert stream_tile_px(sim) % sim.params.noise_block_px == 0
    small = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=(2000, 2000))
    assert not choose_streamed(small, limit_bytes=8 * GiB)
    assert not choose_streamed(sim, limit_bytes=8 * GiB, focal_plane="coarse")  # needs the whole frame
    upsampled = Simulator(BASE, input_pixel_m=5.0, input_shape=(2000, 2000))  # output finer than the input
    assert not choose_streamed(upsampled, limit_bytes=0.5 * GiB)


def test_cli_streams_when_the_full_frame_does_not_fit(tmp_path, monkeypatch):
    """`satchain simulate` on the streamed path: says so, writes the TIFF (equal to the full-frame result)
    and its preview, and leaves no scratch folder."""
    import satchain.cli.main as cli
    from satchain.io import images as io
    img = make_scene((700, 840), np.random.default_rng(3), rectangles=6).astype(np.float32)
    inp = tmp_path / "in.tif"
    io.write_tiff(inp, img, pixel_m=PIXEL_M)
    runner = CliRunner()
    common = ["--preset", "ankarasat3", "--units", "reflectance", "--no-noise"]
    r = runner.invoke(cli.app, ["simulate", str(inp), *common, "-o", str(tmp_path / "full.tif")])
    assert r.exit_code == 0, r.output
    from satchain.engine import georaster

    monkeypatch.setattr(georaster, "_in_memory", lambda *a, **k: False)  # a raster input's plan
    r = runner.invoke(cli.app, ["simulate", str(inp), *common, "-o", str(tmp_path / "s.tif")])
    assert r.exit_code == 0, r.output
    assert "streamed" in r.output
    a, meta = io.read_image(tmp_path / "s.tif")
    b, _ = io.read_image(tmp_path / "full.tif")
    assert a.shape == b.shape and np.max(np.abs(a - b)) <= 1e-6
    assert (tmp_path / "s.png").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_a_frame_no_larger_than_one_window_is_formed_whole():
    """Tiling would save no memory: the streamed tiles are slices of the exact full-frame image."""
    from satchain.engine.stream import FarField

    img = make_scene((1400, 1400), np.random.default_rng(5))
    sim = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=img.shape, params=SimParams(stream_tile_px=512))
    coarse = sim.decimate(ArraySource(img, pixel_m=PIXEL_M))
    far = FarField(sim, coarse, margin_px=sim.params.stream_margin_px)
    assert far.image is not None
    np.testing.assert_array_equal(_assemble(sim, coarse, far=far), sim.form_image(coarse))


def test_the_far_field_on_a_dividing_output_grid_equals_its_matrix_dft(case):
    """Integer ratios: the far field's band is transformed onto the whole output grid by FFTs (its rows once,
    each band of output rows once); it equals the matrix DFT at each tile's pixels. A ratio that does not
    divide the frame keeps the matrix DFT."""
    from satchain.engine.stream import FarField

    src, coarse, _ = case
    p = SimParams(stream_tile_px=64, stream_margin_px=16)
    sim = Simulator(BASE, input_pixel_m=PIXEL_M, input_shape=src.shape_px, params=p)
    fft, matrix = (FarField(sim, coarse, margin_px=16) for _ in range(2))
    assert fft.image is None and fft._grid is not None
    matrix._grid = None
    ny, nx = sim.output_shape
    scale = max(float(np.ptp(fft.tile((0, ny), (0, nx)))), 1e-30)
    for rows in ((0, 64), (64, 128), (ny - 40, ny)):
        for cols in ((0, 64), (128, 192), (nx - 30, nx)):
            np.testing.assert_allclose(fft.tile(rows, cols), matrix.tile(rows, cols), rtol=0, atol=1e-11 * scale)
    odd = Simulator(BASE, input_pixel_m=0.0341, input_shape=src.shape_px, params=p)
    assert odd.k_int == (None, None)
    odd_coarse = odd.decimate(src)
    assert FarField(odd, odd_coarse, margin_px=16)._grid is None
