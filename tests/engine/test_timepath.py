"""Pushbroom images formed in time (issue 20, point 2): closed forms and independent integrals of the line of sight
over each row's TDI window, on ground truths whose static image is a known sinusoid or a straight edge."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import j0

import satchain
from satchain import load_preset, measure_edge
from satchain.engine.simulate import Simulator
from satchain.engine.sources import ArraySource
from satchain.tf import pushbroom_otf
from satchain.tf.pushbroom import PushbroomTerms

BASE = load_preset("ankarasat3")
TAU, N = BASE.line_time_s, BASE.detector.tdi_stages
PX = 0.07
K = BASE.gsd_act_m / PX  # 7 input pixels per output pixel
F0 = 0.3  # the grating's frequency, cycles per output pixel


def _grating(axis: str, n: int = 1050) -> np.ndarray:
    """0.5 + 0.3 cos(2 pi F0 s) along ``axis`` (s in output pixels): its image is a sinusoid of the same phase
    (the PSF is symmetric), so a line-of-sight shift d(t) multiplies it by the window mean of exp(2 pi i F0 d)."""
    s = (np.arange(n) + 0.5) / K
    g = 0.5 + 0.3 * np.cos(2 * np.pi * F0 * s)
    return np.tile(g, (n, 1)) if axis == "act" else np.tile(g[:, None], (1, n))


def _images(system, axis: str, seed: int = 0):
    img = _grating(axis)
    src = ArraySource(img, pixel_m=PX)
    static = Simulator(BASE, input_pixel_m=PX, input_shape=img.shape).run(src)
    moving = Simulator(system, input_pixel_m=PX, input_shape=img.shape, motion_seed=seed).run(src)
    return static, moving


def _phasor(static: np.ndarray, axis: str) -> tuple[float, complex]:
    """The static image's (mean, complex amplitude) along ``axis``: static = mean + Re(C exp(2 pi i F0 (s+0.5)))."""
    line = static[static.shape[0] // 2, 20:-20] if axis == "act" else static[20:-20, static.shape[1] // 2]
    s = np.arange(20, 20 + line.size) + 0.5
    e = np.exp(2j * np.pi * F0 * s)
    a = np.linalg.lstsq(np.c_[np.ones(s.size), e.real, -e.imag], line, rcond=None)[0]
    return float(a[0]), complex(a[1], a[2])


def _window_mean(d, i: int) -> complex:
    """mean over row i's window [i dt, (i + N) dt] of exp(2 pi i F0 d(t)), by quadrature."""
    re = quad(lambda t: math.cos(2 * math.pi * F0 * d(t)), i * TAU, (i + N) * TAU, limit=400)[0]
    im = quad(lambda t: math.sin(2 * math.pi * F0 * d(t)), i * TAU, (i + N) * TAU, limit=400)[0]
    return complex(re, im) / (N * TAU)


def test_an_oscillation_with_whole_cycles_in_the_window_multiplies_the_image_by_j0():
    f = 5 / (N * TAU)  # 5 whole cycles per TDI window: every row sees the same blur, J0(2 pi A nu), any phase
    system = BASE.replace({"motion.oscillation": [{"axis": "act", "amplitude_px": 0.5, "frequency_hz": f,
                                                   "phase_deg": 30.0}]})  # fmt: skip
    static, moving = _images(system, "act")
    c = (slice(20, -20), slice(20, -20))
    np.testing.assert_allclose(moving[c] - 0.5, j0(2 * np.pi * F0 * 0.5) * (static[c] - 0.5), atol=2e-6)


@pytest.mark.parametrize(
    ("keys", "axis", "d"),
    [
        ({"motion.oscillation": [{"axis": "act", "amplitude_px": 2.0, "frequency_hz": 200.0, "phase_deg": 40.0}]},
         "act", lambda t: 2.0 * math.sin(2 * math.pi * 200.0 * t + math.radians(40.0))),
        ({"motion.oscillation": [{"axis": "alt", "amplitude_px": 0.7, "frequency_hz": 1234.5, "phase_deg": -70.0}]},
         "alt", lambda t: 0.7 * math.sin(2 * math.pi * 1234.5 * t + math.radians(-70.0))),
        ({"motion.line_rate_error": 0.05}, "alt", lambda t: 0.05 * t / TAU),
    ],
)  # fmt: skip
def test_each_row_is_the_window_mean_of_the_moved_static_image(keys, axis, d):
    static, moving = _images(BASE.replace(keys), axis)
    mean, c = _phasor(static, axis)
    for i in (25, 31, 44, 58, 70):
        h = _window_mean(d, i)
        line = moving[i, 20:-20] if axis == "act" else moving[20:-20, i]
        s = np.arange(20, 20 + line.size) + 0.5
        if axis == "act":
            expect = mean + np.real(c * np.exp(2j * np.pi * F0 * s) * h)
            np.testing.assert_allclose(line, expect, atol=1e-4)
        else:  # along ALT the row index is the time: check row i of every column
            expect = mean + np.real(c * np.exp(2j * np.pi * F0 * (i + 0.5)) * h)
            np.testing.assert_allclose(moving[i, 20:-20], expect, atol=1e-4)


def test_earth_rotation_shears_and_scales_a_5_degree_edge_as_predicted():
    system = BASE.replace({"orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True})
    g = PushbroomTerms(system).geometry()
    sig, e = g["shear_act_px_per_line"], g["alt_scale"] - 1.0
    assert abs(sig) > 0.05 and 0.005 < e < 0.012  # the equator crossing of a sun-synchronous orbit
    n, t5 = 2100, math.tan(math.radians(5.0))
    y, x = np.mgrid[0:n, 0:n] + 0.5
    vertical = np.where(x - (n / 2 + (y - n / 2) * t5) > 0, 0.6, 0.2)
    horizontal = np.where(y - (n / 2 + (x - n / 2) * t5) > 0, 0.6, 0.2)
    # row i samples the ground at y = i (1 + e), x = j + sigma i: the edge x_g = c + y_g tan 5 appears at
    # x_j = c' + i ((1 + e) tan 5 - sigma), the edge y_g = c + x_g tan 5 at i = c' + j tan 5 / (1 + e - sigma tan 5)
    v = measure_edge(satchain.simulate_image(vertical, system, pixel_m=PX).image[40:260, 120:180])
    h = measure_edge(satchain.simulate_image(horizontal, system, pixel_m=PX).image[120:180, 40:260])
    assert v.angle_deg == pytest.approx(math.degrees(math.atan((1 + e) * t5 - sig)), abs=0.05)
    assert 90.0 - h.angle_deg == pytest.approx(math.degrees(math.atan(t5 / (1 + e - sig * t5))), abs=0.05)


def test_jitter_is_a_seeded_realisation_whose_blur_is_the_budgets():
    keys = {"motion.jitter_psd": {"axis": "act", "frequency_hz": [5e3, 5e4], "psd_px2_per_hz": [3.6e-6, 3.6e-6]}}
    system = BASE.replace(keys)
    static, a = _images(system, "act", seed=1)
    _, b = _images(system, "act", seed=1)
    _, c = _images(system, "act", seed=2)
    np.testing.assert_array_equal(a, b)  # the same seed, the same motion
    assert np.abs(a - c).max() > 1e-4  # another seed, another realisation
    ratio = np.sum((a[20:-20] - 0.5) * (static[20:-20] - 0.5)) / np.sum((static[20:-20] - 0.5) ** 2)
    nu = F0  # cycles per pixel: the budget's exp(-2 pi^2 sigma_blur^2 nu^2), sigma^2 = 0.162 px^2
    budget = PushbroomTerms(system).components()["jitter_psd_act"](np.array([nu / BASE.detector.pitch_x_m / 1e3]),
                                                                   np.array([0.0]))  # fmt: skip
    assert ratio == pytest.approx(float(np.real(budget[0])), abs=0.02)
    assert float(np.real(budget[0])) == pytest.approx(math.exp(-2 * math.pi**2 * 0.162 * nu**2), abs=0.01)


def test_the_time_grid_is_fine_enough_and_the_image_does_not_depend_on_the_tiling(monkeypatch, tmp_path):
    f = 4465.0
    system = BASE.replace({"motion.oscillation": [{"axis": "act", "amplitude_px": 0.8, "frequency_hz": f}]})
    _, coarse_grid = _images(system, "act")
    monkeypatch.setattr(pushbroom_otf, "SAMPLES_PER_PERIOD", 4 * pushbroom_otf.SAMPLES_PER_PERIOD)  # the time grid
    _, fine_grid = _images(system, "act")
    assert np.abs(coarse_grid - fine_grid).max() < 1e-3  # the convergence level
    monkeypatch.undo()
    import rasterio
    from rasterio import Affine

    from satchain.engine import georaster
    from satchain.engine.files import simulate_file

    img = _grating("act", 700).astype(np.float32)
    src = tmp_path / "g.tif"
    with rasterio.open(src, "w", driver="GTiff", width=700, height=700, count=1, dtype="float32",
                       crs="EPSG:32636", transform=Affine(PX, 0, 5e5, 0, -PX, 4e6)) as dst:  # fmt: skip
        dst.write(img, 1)
    whole = satchain.simulate_image(src, system, units="reflectance")
    monkeypatch.setattr(georaster, "_in_memory", lambda *a, **k: False)  # streamed, in tiles
    r = simulate_file(src, tmp_path / "s.tif", system, units="reflectance", noise=False)
    with rasterio.open(r.path) as o:
        streamed = o.read(1)
    assert r.streamed and np.abs(streamed - whole.image).max() < 1e-5


def test_without_motion_keys_the_static_engine_is_untouched():
    sim = Simulator(BASE, input_pixel_m=PX, input_shape=(700, 700))
    assert sim.time_path is None and "detector" in sim._exclude and len(sim._exclude) == 1


def test_drifts_on_both_axes_factor_exactly_into_row_shifts_and_one_mean(monkeypatch):
    import dataclasses

    system = BASE.replace({"orbit.latitude_deg": 30.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True,
                           "motion.line_rate_error": 0.02})  # fmt: skip
    img = _grating("act", 700) * _grating("alt", 700)
    sim = Simulator(system, input_pixel_m=PX, input_shape=img.shape)
    fast = sim.run(ArraySource(img, pixel_m=PX))
    assert sim.time_path.moves_x and sim.time_path.moves_y and not sim.time_path.line_of_sight
    sim.set_time_path(dataclasses.replace(sim.time_path, line_of_sight=True))  # the general mean over time samples
    general = sim.run(ArraySource(img, pixel_m=PX))
    assert np.abs(fast - general).max() < 1e-9
