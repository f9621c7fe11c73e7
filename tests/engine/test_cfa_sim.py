"""Issue 32, points 4 and 7 (Bayer): the raw mosaic of a colour camera simulated through the engine
(satchain.engine.cfa_sim.simulate_cfa) and measured (satchain.prediction.cfa.measure_cfa).

The reference camera (ankarasat3) with ``[detector] cfa`` images a neutral 5-degree slanted edge, noise-free:
each raw colour plane, measured on its own grid (red and blue: every other row and column; green: the quincunx
turned onto its sqrt(2) px grid), has the MTF that satchain.tf.cfa predicts from that colour's system OTF at its
Nyquist within 0.02, for every pattern; the three demosaicing methods' luminance MTF50 and false colour are
reported side by side, with what physics fixes about them asserted: bilinear interpolation is a low-pass (its
MTF50 below a perfect interpolation's) and shows the most false colour; far from the edge no method adds colour
to what the optics themselves give; a uniform grey scene stays exactly grey. Noise is drawn per photosite from
its own colour's radiometry (mean and variance against satchain.radiometry); a spectral scene gives each colour
its own band reflectance (integrated here from the material's spectrum); a window keeps the pattern's phase.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from satchain import load_preset
from satchain.config.sections_cfa import cfa_response, colour_system
from satchain.engine.cfa import cfa_masks
from satchain.engine.cfa_sim import simulate_cfa
from satchain.errors import ConfigError
from satchain.prediction.budget import budget
from satchain.prediction.cfa import measure_cfa
from satchain.scene.layout import layout_from_dict
from satchain.scene.materials import material

PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")
COLOURS = ("red", "green", "blue")
N_PX = 128  # the image, photosites a side
OVERSAMPLE = 7  # scene pixels per photosite
TOL = 0.02  # issue 32 point 7


def camera(pattern: str = "RGGB"):
    return load_preset("ankarasat3").replace({"detector.cfa": pattern})


def edge_layout(gsd_m: float, *, bright=0.8, dark=0.1, n=N_PX, **materials):
    w = n * gsd_m
    item = {"kind": "slanted_edge", "id": "edge", "center_m": [w / 2 + 0.3 * gsd_m, w / 2], "size_m": 2 * w,
            "angle_deg": 5.0, "bright": bright, "dark": dark}  # fmt: skip
    if materials:
        item = {k: v for k, v in item.items() if k not in ("bright", "dark")} | materials
    return layout_from_dict({"scene": {"width_m": w, "height_m": w, "background": 0.3}, "items": [item]})


@pytest.fixture(scope="module")
def measured():
    """{pattern: CFAMeasurement} of the neutral edge, noise-free."""
    out = {}
    for pattern in PATTERNS:
        cam = camera(pattern)
        images = simulate_cfa(edge_layout(cam.gsd_act_m), cam, pixel_m=cam.gsd_act_m / OVERSAMPLE)
        out[pattern] = measure_cfa(images, (8, 8, N_PX - 8, N_PX - 8), system=cam)
    return out


def test_the_budget_of_a_colour_camera_still_works():
    b = budget(camera())
    assert b.system.detector.cfa == "RGGB"
    assert 0.0 < b.mtf_at_nyquist_act < 1.0


@pytest.mark.parametrize("pattern", PATTERNS)
def test_each_raw_colour_plane_has_its_predicted_mtf_at_its_nyquist(measured, pattern):
    m = measured[pattern]
    assert abs(m.normal_deg + 5.0) < 0.1  # the edge found where it was drawn
    for colour in COLOURS:
        p = m.planes[colour]
        assert p.measured_at_grid_nyquist == pytest.approx(p.predicted_at_grid_nyquist, abs=TOL), colour
        assert p.measured_at_zone_nyquist == pytest.approx(p.predicted_at_zone_nyquist, abs=TOL), colour
        assert p.measured_mtf50_cy_per_px == pytest.approx(p.predicted_mtf50_cy_per_px, abs=0.01), colour
    # where the planes sample: red and blue at 1/(4p), green's grid at 1/(2 sqrt2 p), its zone at 1/(2p) along
    # the axes (along the 5 deg normal: 1 / (2 (cos 5 + sin 5)) for the diamond |fx| + |fy| <= 1/2)
    t = math.radians(abs(m.normal_deg))
    assert m.planes["red"].f_grid_cy_per_px == 0.25 and m.planes["blue"].f_grid_cy_per_px == 0.25
    assert m.planes["green"].f_grid_cy_per_px == pytest.approx(1 / (2 * math.sqrt(2)), rel=1e-12)
    assert m.planes["green"].f_zone_cy_per_px == pytest.approx(0.5 / (math.cos(t) + math.sin(t)), rel=1e-9)
    # red sees the most diffraction, blue the least (the colours' own OTFs, measured)
    mtf = {c: m.planes[c].measured_at_grid_nyquist for c in ("red", "blue")}
    assert mtf["red"] < mtf["blue"]


def test_all_four_patterns_give_the_same_plane_mtfs(measured):
    for colour in COLOURS:
        pred = [measured[p].planes[colour].predicted_at_grid_nyquist for p in PATTERNS]
        assert max(pred) - min(pred) < 1e-4  # the pattern moves the lattice, never the colour's OTF (the normal
        # each pattern's edge fit finds differs by a few hundredths of a degree)
        got = [measured[p].planes[colour].measured_at_grid_nyquist for p in PATTERNS]
        assert max(got) - min(got) < 0.01, colour


def test_demosaicing_methods_side_by_side(measured):
    m = measured["RGGB"]
    fig = m.methods
    # the three colour planes themselves (a perfect interpolation) read the predicted luminance MTF50
    assert fig["true"].mtf50_cy_per_px == pytest.approx(m.luminance_mtf50_predicted, abs=0.01)
    # bilinear interpolation is a low-pass: its luminance is blurred beyond the optics'
    assert fig["bilinear"].mtf50_cy_per_px < m.luminance_mtf50_predicted - 0.03
    assert fig["bilinear"].mtf50_cy_per_px < fig["malvar2004"].mtf50_cy_per_px
    assert fig["bilinear"].mtf50_cy_per_px < fig["menon2007"].mtf50_cy_per_px
    # at the edge bilinear shows the most false colour
    for method in ("malvar2004", "menon2007"):
        assert fig["bilinear"].false_colour_peak > fig[method].false_colour_peak
        assert fig["bilinear"].false_colour_rms > fig[method].false_colour_rms
    # away from the edge no method adds colour to what the optics give (each colour's PSF tail differs)
    for method in ("bilinear", "malvar2004", "menon2007"):
        assert fig[method].flat_peak < 0.005
        assert abs(fig[method].flat_peak - fig["true"].flat_peak) < 5e-4
    rows = m.method_rows()
    assert [r["method"] for r in rows] == ["true", "bilinear", "malvar2004", "menon2007"]


@pytest.mark.parametrize("pattern", ["RGGB", "GBRG"])
def test_a_uniform_grey_scene_is_grey(pattern):
    cam = camera(pattern)
    out = simulate_cfa(np.full((140, 140), 0.37), cam, pixel_m=0.098)
    np.testing.assert_allclose(out.raw, 0.37, rtol=1e-7)  # the engine's own precision (float32 scene, filters)
    for rgb in out.rgb.values():
        np.testing.assert_allclose(rgb, 0.37, rtol=1e-7)
        assert np.abs(rgb - rgb[..., 1:2]).max() < 1e-8  # no colour


def test_noise_per_photosite_from_its_own_colours_radiometry():
    from satchain import radiometry

    cam = camera()
    rho = 0.4
    out = simulate_cfa(np.full((448, 448), rho), cam, pixel_m=0.07, units="electrons", noise=True, seed=3,
                       methods=())  # fmt: skip
    det = cam.detector
    dark = det.dark_current_e_per_s * cam.integration_time_s * det.tdi_stages
    for colour, m in out.masks.items():
        mean = float(radiometry.signal_electrons(colour_system(cam, colour), rho)) + dark
        v = out.raw[m]
        assert v.mean() == pytest.approx(mean, rel=3 * math.sqrt(mean) / mean / math.sqrt(v.size) + 1e-9)
        var = mean + det.read_noise_e**2  # Poisson shot + read (CCD: once)
        assert v.var() == pytest.approx(var, rel=4 * math.sqrt(2.0 / v.size))
    # the colours differ (their QE x response), and the seed reproduces the draw
    assert out.raw[out.masks["green"]].mean() > out.raw[out.masks["red"]].mean()
    again = simulate_cfa(np.full((448, 448), rho), cam, pixel_m=0.07, units="electrons", noise=True, seed=3,
                         methods=())  # fmt: skip
    np.testing.assert_array_equal(again.raw, out.raw)


def _band_reflectance(name: str, colour: str, det) -> float:
    """The material's reflectance over the colour's response, by the trapezoid rule on a 0.5 nm grid."""
    mat, resp = material(name), cfa_response(det, colour)
    lam = np.arange(380e-9, 780e-9, 0.5e-9)
    r = resp.at(lam)
    rho = np.interp(lam, mat.wavelengths_m, mat.reflectance)
    return float(np.trapezoid(rho * r, lam) / np.trapezoid(r, lam))


def test_a_spectral_scene_gives_each_colour_its_band_and_a_window_keeps_the_phase():
    cam = camera("GRBG")
    gsd = cam.gsd_act_m
    lay = edge_layout(gsd, n=64, bright_material="white_paint", dark_material="red_brick")
    full = simulate_cfa(lay, cam, pixel_m=gsd / 5, methods=())
    # far from the edge each colour plane is the material's reflectance in that colour's band, but for the
    # obscured Airy pattern's far tail (its energy beyond R falls as 1/R), which moves each plateau towards the
    # other by the same amount: their sum is exact, each within 1 % of the step
    for colour in COLOURS:
        plane = full.planes[colour]
        bright = _band_reflectance("white_paint", colour, cam.detector)
        dark = _band_reflectance("red_brick", colour, cam.detector)
        assert float(plane[32, 61] + plane[32, 2]) == pytest.approx(bright + dark, abs=5e-4), colour
        assert float(plane[32, 61]) == pytest.approx(bright, abs=0.01 * (bright - dark)), colour
        assert float(plane[32, 2]) == pytest.approx(dark, abs=0.01 * (bright - dark)), colour
    # a window starting at an odd photosite keeps the full array's phase (the colours differ: a wrong phase shows)
    win = simulate_cfa(lay, cam, pixel_m=gsd / 5, window=(5 * 9, 5 * 7, 5 * 40, 5 * 50), methods=())
    assert win.origin == (9, 7)
    crop = full.raw[9 + 12 : 9 + 28, 7 + 12 : 7 + 38]
    np.testing.assert_allclose(win.raw[12:28, 12:38], crop, atol=2e-3)
    np.testing.assert_array_equal(win.masks["red"], cfa_masks(win.raw.shape, "GRBG", origin=(9, 7))["red"])


def test_bad_input_is_one_line():
    with pytest.raises(ConfigError, match=r"detector.cfa = None"):
        simulate_cfa(np.full((70, 70), 0.2), load_preset("ankarasat3"), pixel_m=0.098)
    with pytest.raises(Exception, match=r"units = 'radiance'"):
        simulate_cfa(np.full((70, 70), 0.2), camera(), pixel_m=0.098, units="radiance")
    with pytest.raises(ConfigError, match=r"window = .*must fall on a photosite's edge"):
        simulate_cfa(np.full((70, 70), 0.2), camera(), pixel_m=0.098, window=(3, 0, 20, 20))


def test_a_vegetation_scene_through_a_bayer_camera():
    """PROSAIL vegetation (400-2500 nm) seen through the default colour responses (380-780 nm, their noise floor
    below 400 nm): green vegetation is greener than it is red or blue, on the raw mosaic's own photosites."""
    cam = camera("RGGB")
    gsd = cam.gsd_act_m
    lay = edge_layout(gsd, n=32, bright_material="green_vegetation", dark_material="asphalt")
    img = simulate_cfa(lay, cam, pixel_m=gsd / 5, methods=())
    far = {c: float(img.planes[c][16, 29]) for c in COLOURS}  # the vegetation plateau
    assert far["green"] > far["red"] and far["green"] > far["blue"]
