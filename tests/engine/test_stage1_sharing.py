"""One stage 1 and one frame transform per pixel grid (satchain.engine.bands_shared.group_decimation,
Simulator.frame_spectrum / own_band, BandSpectrum.restrict): the band of a wider transform restricted to a narrower
one is that narrower transform (and numpy's fft2), an image formed from a shared wider spectrum is the image formed
from its own, a stage 1 with a pass band wider than the optics changes the image only within the engine's accuracy,
and simulate_bands' bands give the images they gave without the sharing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import satchain.engine.bands as bands_module
from satchain import load_preset
from satchain.engine.bands import simulate_bands
from satchain.engine.bands_shared import GROUP_STOPBAND_RATIO, group_decimation
from satchain.engine.simulate import SimParams, Simulator, decimation_factor
from satchain.engine.sources import as_ground_truth
from satchain.engine.spectral import tile_band_spectrum
from satchain.errors import ConfigError
from satchain.scene.layout import Scene
from satchain.scene.targets import SlantedEdge

EARTH_YAW = {"orbit.earth_rotation": True, "orbit.inclination_deg": 97.7, "orbit.yaw_steering": True,
             "orbit.latitude_deg": 40.0}  # fmt: skip


def _d(f_pass: float, ratio: float) -> int:
    """Closed form of stage 1's decimation: the largest D with 1 / (2 D) >= ratio * f_pass, at least 1."""
    return max(1, math.floor(0.5 / (ratio * f_pass) - 1e-9)) if ratio * f_pass < 0.25 else 1


def _expected_my(ny: int, by: int) -> np.ndarray:
    if 2 * by + 1 >= ny:  # every row, in fftfreq order
        return np.array([m if m <= (ny - 1) // 2 else m - ny for m in range(ny)])
    return np.array([*range(by + 1), *range(-by, 0)])


# ---------------------------------------------------------------- BandSpectrum.restrict


@settings(max_examples=25, deadline=None)
@given(ny=st.integers(8, 120), nx=st.integers(8, 120), data=st.data())
def test_restrict_is_the_narrower_transform_and_numpys_fft2(ny, nx, data):
    by_big = data.draw(st.integers(0, ny), label="by_big")  # up to past the whole rows (2 by + 1 >= ny)
    by_small = data.draw(st.integers(0, by_big), label="by_small")
    bx_big = data.draw(st.integers(0, nx // 2), label="bx_big")
    bx_small = data.draw(st.integers(0, bx_big), label="bx_small")
    a = np.random.default_rng(ny * 1000 + nx).standard_normal((ny, nx)).astype(np.float32)
    got = tile_band_spectrum(a, by=by_big, bx=bx_big).restrict(by=by_small, bx=bx_small)
    own = tile_band_spectrum(a, by=by_small, bx=bx_small)
    want_my = _expected_my(ny, by_small)
    assert np.array_equal(got.my, own.my) and np.array_equal(got.my, want_my)
    assert np.array_equal(got.mx, own.mx) and np.array_equal(got.mx, np.arange(bx_small + 1))
    assert tuple(got.shape) == tuple(own.shape) == (ny, nx)
    assert got.values.shape == (want_my.size, bx_small + 1)
    ref = np.fft.fft2(a.astype(np.float64))[np.mod(want_my, ny)[:, None], np.arange(bx_small + 1)[None, :]]
    for v in (own.values, ref):
        assert np.allclose(got.values, v, rtol=1e-5, atol=1e-5 * np.abs(v).max())
    assert np.array_equal(got.cx, own.cx)


@pytest.mark.parametrize(("ny", "nx", "held", "asked"), [
    (40, 30, (5, 6), (5, 7)),  # a column beyond the held band
    (40, 30, (5, 6), (6, 6)),  # a row beyond it
    (40, 30, (5, 6), (20, 6)),  # every row, of a spectrum holding 11 of 40
    (41, 31, (3, 15), (3, 16)),
])  # fmt: skip
def test_restrict_outside_the_held_band_raises(ny, nx, held, asked):
    a = np.random.default_rng(1).standard_normal((ny, nx))
    spec = tile_band_spectrum(a, by=held[0], bx=held[1])
    with pytest.raises(ValueError, match="outside"):
        spec.restrict(by=asked[0], bx=asked[1])


# ---------------------------------------------------------------- form_image from a shared spectrum


@pytest.mark.parametrize("yaw", [False, True])
def test_form_image_from_a_wider_frame_spectrum_is_the_image_from_its_own(yaw):
    """ankarasat3 (under yaw steering with the Earth's rotation: the frame turned, the rows formed in time) on a
    280 px random ground at 0.035 m: the image formed from the frame's transform over a wider band (1.3 x the
    cutoff, the coarse Nyquist, beyond it) equals the image formed from the coarse grid within 1e-6 (0 measured:
    the same values restricted)."""
    system = load_preset("ankarasat3")
    system = system.replace(EARTH_YAW) if yaw else system
    g = np.random.default_rng(7).random((280, 280)).astype(np.float32)
    sim = Simulator(system, input_pixel_m=0.035, input_shape=g.shape)
    assert (sim.yaw_deg != 0.0) == yaw and sim.D == 4
    coarse = sim.decimate(as_ground_truth(g, pixel_m=0.035))
    own = sim.form_image(coarse)
    assert own.shape == sim.output_shape == (20, 20)
    for f_band in (1.3 * sim.f_cut, 0.5 / sim.D, 1.0):
        spec = sim.frame_spectrum(coarse, f_band=f_band)
        assert spec.values.shape[1] > sim.own_band(spec).values.shape[1]  # wider than its own band
        assert np.abs(sim.form_image(None, spectrum=spec) - own).max() <= 1e-6
    with pytest.raises(ConfigError, match="coarse or spectrum"):
        sim.form_image(None)


# ---------------------------------------------------------------- SimParams.pass_cy_per_px


def test_pass_band_below_zero_is_refused_naming_it():
    with pytest.raises(ConfigError, match=r"pass_cy_per_px = -0\.1"):
        SimParams(pass_cy_per_px=-0.1)


def _cosines_and_edge(n: int) -> np.ndarray:
    """Three 2-D cosines below ankarasat3's optical cutoff (0.0665 cy/px at 0.035 m) and a step edge."""
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    g = 0.5 + 0.1 * np.cos(2 * np.pi * (0.02 * x + 0.01 * y)) + 0.08 * np.cos(2 * np.pi * (0.045 * y - 0.013 * x) + 0.3)
    g += 0.05 * np.cos(2 * np.pi * 0.06 * x + 1.0) + 0.2 * (x + 0.1 * y > n / 2)
    return g.astype(np.float32)


@pytest.mark.parametrize(("f_pass", "ratio"), [(0.09, 1.25), (0.13, 1.25), (0.2, 1.25), (0.1, 1.8), (0.03, 1.25)])
def test_a_wider_stage1_pass_band_leaves_the_image(f_pass, ratio):
    """ankarasat3 at 0.035 m (cutoff 0.0665 cy/px, D = 4 by default) on 252 px (a multiple of every D here, so the
    mirror border is exact on each coarse grid): a pass band above the cutoff decimates by the closed form's D
    (4, 3, 1, 2; below the cutoff it is the cutoff) and the image is the default's within 1e-6 of the ground's
    range (1.1e-7 to 2.0e-7 measured). On 280 px, D = 3 leaves 3.2e-5: not a multiple of 3, the engine's coarse
    mirror is approximate, whatever the pass band (stopband_ratio 2.2 alone gives 4.4e-5)."""
    system, g = load_preset("ankarasat3"), _cosines_and_edge(252)
    src = as_ground_truth(g, pixel_m=0.035)
    ref_sim = Simulator(system, input_pixel_m=0.035, input_shape=g.shape)
    p = SimParams(pass_cy_per_px=f_pass, stopband_ratio=ratio)
    sim = Simulator(system, input_pixel_m=0.035, input_shape=g.shape, params=p)
    assert sim.f_cut == ref_sim.f_cut and 0.066 < sim.f_cut < 0.067
    assert sim.f_pass == max(f_pass, sim.f_cut)
    assert sim.D == decimation_factor(sim.f_pass, ratio) == _d(sim.f_pass, ratio)
    assert ref_sim.D == _d(ref_sim.f_cut, 1.8) == 4
    got, ref = sim.run(src, units="reflectance"), ref_sim.run(src, units="reflectance")
    assert np.abs(got - ref).max() <= 1e-6 * float(np.ptp(g))


# ---------------------------------------------------------------- group_decimation


_band = st.tuples(st.sampled_from(["a", "b", "c"]), st.floats(0.01, 0.6))


@settings(max_examples=25, deadline=None)
@given(bands=st.dictionaries(st.integers(0, 20), _band, min_size=1, max_size=8), ratio=st.floats(1.3, 3.0))
def test_group_decimation_joins_a_grid_only_when_it_decimates_no_less(bands, ratio):
    got = group_decimation(bands, ratio)
    assert set(got) == set(bands)
    shared = min(ratio, GROUP_STOPBAND_RATIO)
    for grid in {g for g, _ in bands.values()}:
        members = {i: f for i, (g, f) in bands.items() if g == grid}
        widest = max(members.values())
        joiners = set()
        for i, f in members.items():
            if len(members) == 1:
                assert got[i] == (0.0, ratio)
            elif got[i] != (0.0, ratio):
                assert got[i] == (widest, shared)
                assert decimation_factor(widest, shared) >= decimation_factor(f, ratio)
                assert _d(widest, shared) >= _d(f, ratio)
                joiners.add(i)
            else:  # stays on its own plan: sharing would decimate less
                assert _d(widest, shared) < _d(f, ratio)
        assert len({got[i] for i in joiners}) <= 1


def test_decimation_factor_is_the_closed_form():
    for f in np.linspace(0.005, 0.6, 120):
        for r in (1.05, 1.25, 1.8, 3.0):
            assert decimation_factor(float(f), r) == _d(float(f), r)


# ---------------------------------------------------------------- simulate_bands' seam


@pytest.fixture(scope="module")
def edge_scene() -> Scene:
    items = (SlantedEdge("a", center_m=(9.8, 9.8), size_m=14.0, angle_deg=5.0, bright=0.98, dark=0.02),)
    return Scene(19.6, 19.6, items, 0.3)


def test_pan_alone_on_its_grid_is_formed_as_before(edge_scene):
    """PAN, alone on its pixel grid, is the same array (DN, noise) whether the MS bands are formed with it or not."""
    pms = load_preset("ankarasat3-pms")
    one = simulate_bands(edge_scene, pms, pixel_m=0.07, noise=True, units="dn", seed=3, bands=["pan"])
    every = simulate_bands(edge_scene, pms, pixel_m=0.07, noise=True, units="dn", seed=3)
    assert np.array_equal(one["pan"].image, every["pan"].image)


def test_ms_bands_under_yaw_steering_equal_their_images_without_sharing(edge_scene, monkeypatch):
    """ankarasat3-pms steered at 40 deg with the Earth's rotation, the frame's whole margin decimated exactly
    (exact_border_px 64 >= the MS bands' 32-pixel far margin): each MS band within 1e-6 of the image formed with
    its own stage 1 (blue and green by D = 1, not the shared 2; 8.0e-7 measured). With the default
    exact_border_px (16) blue and green differ by 6.2e-6 and 4.3e-6: every pixel of this 10 x 10 image lies within
    the far margin of the ground's edge, where the engine's coarse border continuation is approximate; shared and
    unshared are then both ~3e-6 from a 512 / 128 margin reference."""
    system = load_preset("ankarasat3-pms").replace(EARTH_YAW)
    params = SimParams(exact_border_px=64)
    run = {"params": params, "pixel_m": 0.07, "noise": False, "units": "reflectance"}
    factors, decimate = [], Simulator.decimate

    def recorded(self, *a, **k):
        factors.append(self.D)
        return decimate(self, *a, **k)

    monkeypatch.setattr(Simulator, "decimate", recorded)
    shared = simulate_bands(edge_scene, system, **run)
    assert factors == [2, 2, 2, 2, 2]  # PAN, then the MS bands on the grid's shared stage 1
    factors.clear()
    monkeypatch.setattr(bands_module, "group_decimation", lambda b, r: {i: (0.0, float(r)) for i in b})
    alone = simulate_bands(edge_scene, system, **run)
    assert factors == [2, 1, 1, 2, 2]  # blue and green on their own
    for name in system.band_names:
        assert np.abs(shared[name].image - alone[name].image).max() <= 1e-6, name
