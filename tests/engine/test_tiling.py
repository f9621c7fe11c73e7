"""Tiled == untiled: the decimation tiles (stage 1) must not show in the result."""

from __future__ import annotations

import numpy as np
from _reference import make_scene
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from satchain import load_preset
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import ArraySource

BASE = load_preset("ankarasat3")
MiB = 2**20


def _run(image, pixel_m, **params):
    sim = Simulator(BASE, input_pixel_m=pixel_m, input_shape=image.shape, params=SimParams(**params))
    return sim, sim.run(ArraySource(image, pixel_m=pixel_m))


def test_small_tile_budget_gives_many_tiles_and_the_same_image():
    img = make_scene((1400, 1260), np.random.default_rng(5))
    one, a = _run(img, 0.035)
    many, b = _run(img, 0.035, max_tile_bytes=12 * MiB)
    assert len(one.tiles) == 1 and len(many.tiles) > 10
    assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(a))


@settings(max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(
    rows=st.integers(200, 760),
    cols=st.integers(200, 760),
    tile_mib=st.integers(12, 24),
    pixel_m=st.sampled_from([0.035, 0.04, 0.05]),
    border=st.sampled_from(["symmetric", "periodic", "constant"]),
)
def test_tiled_equals_untiled(rows, cols, tile_mib, pixel_m, border):
    img = make_scene((rows, cols), np.random.default_rng(rows * 1000 + cols), rectangles=5)
    _, a = _run(img, pixel_m, border=border, border_value=0.3)
    _, b = _run(img, pixel_m, border=border, border_value=0.3, max_tile_bytes=tile_mib * MiB)
    assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(a))


def test_progress_reports_every_tile():
    img = make_scene((700, 700), np.random.default_rng(6), rectangles=3)
    sim = Simulator(BASE, input_pixel_m=0.035, input_shape=img.shape, params=SimParams(max_tile_bytes=12 * MiB))
    calls = []
    sim.run(ArraySource(img, pixel_m=0.035), progress=lambda done, total: calls.append((done, total)))
    n = len(sim.tiles)
    assert calls == [(i, n) for i in range(1, n + 1)]


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    ny=st.integers(1, 5000),
    nx=st.integers(1, 5000),
    tile_coarse=st.integers(16, 2000),
    D=st.integers(1, 14),
    margin_blocks=st.integers(0, 60),
)
def test_fast_tiles_are_balanced_and_cover_the_grid_once(ny, nx, tile_coarse, D, margin_blocks):
    """Equal tiles per axis (no short remainder tile, which costs nearly a full transform), no more of them
    than ``tile_coarse`` needs, each coarse sample in exactly one tile, each input window holding its samples
    with both margins, at D times a fast FFT length."""
    from scipy.fft import next_fast_len

    from satchain.engine.tiling import plan_tiles

    m = margin_blocks * D
    tiles = plan_tiles((ny, nx), D=D, tile_coarse=tile_coarse, margin_px=m, fast=True)
    seen = np.zeros((ny, nx), dtype=np.int32)
    for t in tiles:
        seen[t.coarse.rows, t.coarse.cols] += 1
        for j0, n, i0, length in ((t.coarse.row0, t.coarse.height, t.input.row0, t.input.height),
                                  (t.coarse.col0, t.coarse.width, t.input.col0, t.input.width)):  # fmt: skip
            assert i0 == D * j0 - m and length >= D * n + 2 * m
            if D > 1:
                assert length % D == 0 and next_fast_len(length // D) == length // D
    assert np.all(seen == 1)
    for axis, n in ((0, ny), (1, nx)):
        sizes = sorted({(t.coarse.height, t.coarse.width)[axis] for t in tiles})
        assert len({t.index[axis] for t in tiles}) <= -(-n // tile_coarse)
        assert len(sizes) <= 2 and (len(sizes) == 1 or sizes[0] < sizes[1])  # full tiles, then one shorter
        lengths = {
            (t.input.height, t.input.width)[axis] for t in tiles if (t.coarse.height, t.coarse.width)[axis] == sizes[-1]
        }
        assert len(lengths) == 1
