"""Every band of a banded system (satchain.engine.bands; issue 32 points 3 and 7) on the ankarasat3-pms preset:
each band's edge MTF at its own Nyquist and its SNR against the budget, an injected MS offset recovered by
measuring registration, a single-band system exactly as today, and the rasters and previews written."""

from __future__ import annotations

import json

import numpy as np
import pytest

import satchain
from satchain import load_preset
from satchain.engine.bands import PREVIEW_STRETCH_PCT, simulate_bands, write_band_rasters
from satchain.engine.sensor import sensor_from_system
from satchain.engine.simulate import SimParams, simulate
from satchain.errors import ConfigError
from satchain.measure.edge import measure_edge
from satchain.measure.registration import measure_registration
from satchain.prediction.budget import band_budgets
from satchain.scene.layout import Scene, layout_from_dict
from satchain.scene.targets import SlantedEdge

PMS = "ankarasat3-pms"
P_EDGE = 0.07  # m: 7 scene px per PAN pixel, 28 per MS pixel (the engine's exact integer ratios)
#: (x0, y0, x1, y1) of each edge's region in MS pixels (x 4 on the PAN grid): inside the 120 m squares
ROIS_MS = {"act": (4, 4, 58, 58), "alt": (68, 4, 122, 58)}


def _edges(bright: str, dark: str, background: str) -> Scene:
    """Two 120 m slanted-edge squares (~61 MS px each) of materials: one measures ACT, one ALT."""
    def edge(id_: str, x: float, measures: str) -> dict:
        return {"kind": "slanted_edge", "id": id_, "center_m": [x, 62.5], "size_m": 120.0, "angle_deg": 5.0,
                "measures": measures, "bright_material": bright, "dark_material": dark}  # fmt: skip

    return layout_from_dict({"scene": {"width_m": 250.0, "height_m": 125.0, "background_material": background},
                             "items": [edge("e_act", 62.5, "act"), edge("e_alt", 187.5, "alt")]})  # fmt: skip


def _with_offset(system, name: str, offset_px: tuple[float, float]):
    i = system.band_index(name)
    bands = tuple(b.model_copy(update={"registration_offset_px": offset_px}) if k == i else b
                  for k, b in enumerate(system.bands))  # fmt: skip
    return system.model_copy(update={"bands": bands})


@pytest.fixture(scope="module")
def pms():
    return load_preset(PMS)


def test_every_band_edge_mtf_at_its_nyquist_matches_its_budget(pms):
    """Noise-free, spectral scene (paints on dry grass): every band's slanted-edge MTF at its own Nyquist, ACT and
    ALT, measured on its own pixel grid, within 0.02 of its budget (measured: within 0.004)."""
    result = simulate_bands(_edges("white_paint", "black_paint", "dry_grass"), pms, pixel_m=P_EDGE, noise=False)
    budget = satchain.budget(pms).bands
    assert result.names == pms.band_names
    for band, pred in zip(result, budget, strict=True):
        scale = round(1.96 / band.gsd_m)  # 4 on the PAN grid, 1 on the MS grid
        assert band.image.shape == (int(125.0 / band.gsd_alt_m + 1e-9), int(250.0 / band.gsd_act_m + 1e-9))
        for axis, want in (("act", pred.mtf_at_nyquist_act), ("alt", pred.mtf_at_nyquist_alt)):
            roi = tuple(v * scale for v in ROIS_MS[axis])
            got = measure_edge(band.image, roi=roi, fit_degree=1).mtf_at_nyquist
            assert got == pytest.approx(want, abs=0.02), (band.name, axis, got, want)


def test_every_band_snr_matches_its_budget(pms):
    """Noisy, a uniform ground at the budget's reflectance: each band's SNR (mean signal over the standard deviation,
    in electrons, the dark level taken off) within 5 % of its budget (measured: within 1.4 %; the estimate's own
    1-sigma is 1.1 % on 64 x 64 MS pixels)."""
    rho = pms.illumination.reflectance
    result = simulate_bands(Scene(125.44, 125.44, background=rho), pms, pixel_m=0.245, units="electrons", seed=11)
    for band, pred in zip(result, satchain.budget(pms).bands, strict=True):
        det = band.system.detector
        dark_e = det.dark_current_e_per_s * band.system.integration_time_s * det.tdi_stages
        snr = (band.image.mean() - dark_e) / band.image.std(ddof=1)
        assert snr == pytest.approx(pred.snr, rel=0.05), (band.name, snr, pred.snr)
    # each band's noise is its own: two bands on one grid are uncorrelated
    c = np.corrcoef(result["green"].image.ravel(), result["red"].image.ravel())[0, 1]
    assert abs(c) < 0.05


@pytest.mark.parametrize("offset_px", [(0.30, 0.30), (0.0, -0.30)])
def test_injected_ms_offset_is_recovered_by_registration(pms, offset_px):
    """A 0.30 px registration_offset_px of the red band, as the budget predicts it (static_px), recovered within
    0.02 px by measuring red against green (both MS, one grid; measured: within 0.008). The scene has two materials,
    so one band is an affine function of the other, as the registration model assumes."""
    system = _with_offset(pms, "red", offset_px)
    predicted = band_budgets(system)[system.band_index("red")]["registration"]["static_px"]
    assert (predicted["alt"], predicted["act"]) == pytest.approx(offset_px)
    result = simulate_bands(_edges("white_paint", "black_paint", "black_paint"), system, pixel_m=0.245,
                            noise=False, bands=["green", "red"])  # fmt: skip  (8 scene px per MS px: MS only)
    got = measure_registration(result["green"].image, result["red"].image).offset_px
    assert got == pytest.approx(offset_px, abs=0.02)
    assert result["red"].transform == result["green"].transform  # the transforms stay nominal


def test_whole_pixel_offset_moves_the_image_by_whole_pixels(pms):
    """An offset of (1, -2) band pixels is the image of the unshifted band moved by (1, -2): ``image(y, x) =
    reference(y - 1, x + 2)`` (the registration sign convention). The ground beyond the window is continued by its
    own background (border "constant"), so both windows see the same ground everywhere."""
    scene = Scene(62.72, 62.72, (SlantedEdge("e", center_m=(30.0, 30.0), size_m=40.0, angle_deg=7.0),), 0.2)
    params = SimParams(border="constant", border_value=0.2)
    ref = simulate_bands(scene, pms, pixel_m=0.245, noise=False, bands=["red"], params=params)["red"].image
    moved = simulate_bands(scene, _with_offset(pms, "red", (1.0, -2.0)), pixel_m=0.245, noise=False,
                           bands=["red"], params=params)["red"].image  # fmt: skip
    np.testing.assert_allclose(moved[1:, :-2], ref[:-1, 2:], atol=1e-6)


def _los_mean(amplitude_px: float, f_hz: float, phase_rad: float, t0_s: np.ndarray, window_s: float) -> np.ndarray:
    """The mean of ``amplitude sin(2 pi f t + phase)`` over ``[t0, t0 + window]`` (closed form)."""
    w = 2 * np.pi * f_hz
    a, b = w * t0_s + phase_rad, w * (t0_s + window_s) + phase_rad
    return amplitude_px * (np.cos(a) - np.cos(b)) / (w * window_s)


def test_oscillation_misregisters_bands_by_their_delay(pms):
    """A 20 Hz, 1 px ACT oscillation and the red band 10 mm behind the PAN line (seeing the ground 0.12 s later): the
    offset of red from PAN measured in strips of 20 MS rows matches the closed form within 0.05 px -- content moves
    against the line of sight (:mod:`satchain.engine.timepath`: a pixel sees ``x = j + LOS(t)``), so the offset
    is minus (red's line of sight, averaged over its rows' TDI windows at their time + delay, less PAN's, in MS
    pixels)."""
    system = pms.replace({"motion.oscillation": [{"axis": "act", "amplitude_px": 1.0, "frequency_hz": 20.0}]})
    red = system.band_index("red")
    bands = tuple(b.model_copy(update={"offset_alt_mm": 10.0}) if k == red else b for k, b in enumerate(system.bands))
    system = system.model_copy(update={"bands": bands})
    rng = np.random.default_rng(1)  # squares at random angles: features of every orientation in every strip
    corners = [(x, y) for y in np.arange(4.0, 172.0, 9.0) for x in np.arange(4.0, 74.0, 9.0)]
    items = tuple(SlantedEdge(f"s{k}", center_m=(x + rng.uniform(0, 2), y + rng.uniform(0, 2)), size_m=5.0,
                              angle_deg=float(rng.uniform(-30, 30))) for k, (x, y) in enumerate(corners))
    result = simulate_bands(Scene(78.4, 176.4, items, 0.2), system, pixel_m=P_EDGE, noise=False, bands=["pan", "red"])
    pan, ms = result["pan"].image, result["red"].image
    dt, stages = system.line_time_s, system.detector.tdi_stages  # PAN: 16 stages; red: 1 stage of 4 line times
    delay_s = 10e-3 * dt / system.detector.pitch_y_m
    for r0 in range(0, ms.shape[0] - 19, 20):
        got = measure_registration(pan[4 * r0 : 4 * r0 + 80], ms[r0 : r0 + 20], scale=4).offset_px
        los_pan = _los_mean(1.0, 20.0, 0.0, np.arange(4 * r0, 4 * r0 + 80) * dt, stages * dt).mean() / 4
        los_red = _los_mean(0.25, 20.0, 0.0, np.arange(r0, r0 + 20) * 4 * dt + delay_s, 4 * dt).mean()
        assert got[1] == pytest.approx(-(los_red - los_pan), abs=0.05), (r0, got, los_red - los_pan)
        (o,) = [b for b in band_budgets(system) if b["name"] == "red"][0]["registration"]["oscillations"]
        t_c = np.arange(4 * r0, 4 * r0 + 80) * dt  # the PAN rows' window centres, as the budget's t_c
        phase = 2 * np.pi * o["frequency_hz"] * t_c + np.radians(o["phase_deg"])
        budget_px = np.mean(o["amplitude_px"] * np.sin(phase))
        assert got[1] == pytest.approx(budget_px, abs=0.05), (r0, got, budget_px)  # issue 32: within 0.05 px
        assert got[0] == pytest.approx(0.0, abs=0.05)


def test_single_band_and_grey_scene_identical_to_today(pms):
    """A system without bands, and the PAN band of a banded system on a grey scene, give exactly the image of
    satchain.engine.simulate.simulate (noise and DN included)."""
    scene = Scene(19.6, 19.6, (SlantedEdge("e", center_m=(10.0, 10.0), size_m=12.0, angle_deg=5.0),), 0.2)
    mono = load_preset("ankarasat3")
    today = simulate(scene, mono, pixel_m=0.035, sensor=sensor_from_system(mono), units="dn", noise=True, seed=5)
    got = simulate_bands(scene, mono, pixel_m=0.035, units="dn", noise=True, seed=5)
    assert len(got) == 1 and np.array_equal(got[0].image, today)
    pan = pms.for_band(0)
    today = simulate(scene, pan, pixel_m=0.035, sensor=sensor_from_system(pan), units="dn", noise=True, seed=5)
    got = simulate_bands(scene, pms, pixel_m=0.035, units="dn", noise=True, seed=5, bands=["pan"])
    assert np.array_equal(got["pan"].image, today)
    clean = simulate(scene, mono, pixel_m=0.035)
    assert np.array_equal(simulate_bands(scene, mono, pixel_m=0.035, noise=False)[0].image, clean)


def test_rasters_one_per_grid_with_names_wavelengths_and_georeference(pms, tmp_path):
    import rasterio
    from affine import Affine
    from PIL import Image

    from satchain.io.images import read_image

    scene = layout_from_dict({"scene": {"width_m": 31.36, "height_m": 31.36, "background_material": "dry_grass"},
                              "items": [{"kind": "slanted_edge", "id": "e", "center_m": [15.0, 15.0],
                                         "size_m": 20.0, "bright_material": "green_vegetation",
                                         "dark_material": "asphalt"}]})  # fmt: skip
    result = simulate_bands(scene, pms, pixel_m=0.245, window=(8, 16, 96, 112), units="dn", seed=2)
    paths = write_band_rasters(result, tmp_path)
    assert sorted(paths) == ["false_colour", "ms", "pan", "rgb"]
    with rasterio.open(paths["pan"]) as pan, rasterio.open(paths["ms"]) as ms:
        assert pan.count == 1 and ms.count == 4
        assert ms.descriptions == ("blue", "green", "red", "nir")
        assert pan.descriptions == ("pan",)
        for j, band in enumerate(pms.bands[1:], start=1):
            tags = ms.tags(j)
            assert float(tags["center_wavelength_m"]) == pytest.approx(band.center_wavelength_m, rel=1e-12)
            assert float(ms.tags(j, ns="IMAGERY")["CENTRAL_WAVELENGTH_UM"]) == pytest.approx(
                band.center_wavelength_m * 1e6, rel=1e-5)  # fmt: skip
            np.testing.assert_array_equal(ms.read(j), result[band.name].image.astype(np.uint16))
        # the window's corner (16, 8) scene px of 0.245 m: both grids start there, the MS pixel 4 PAN pixels
        corner = Affine.translation(16 * 0.245, -8 * 0.245)
        assert pan.transform.almost_equals(corner @ Affine.scale(0.49, -0.49))
        assert ms.transform.almost_equals(pan.transform @ Affine.scale(4.0))
        assert (pan.height, pan.width, ms.height, ms.width) == (96 // 2, 112 // 2, 96 // 8, 112 // 8)  # 2, 8 px each
        assert pan.dtypes[0] == "uint16" and pan.crs is None
        desc = json.loads(ms.tags()["TIFFTAG_IMAGEDESCRIPTION"])["satchain"]
        assert desc["band_names"] == ["blue", "green", "red", "nir"] and desc["units"] == "dn"
    img, meta = read_image(paths["ms"], band=3)
    assert meta["pixel_m"] == pytest.approx(1.96) and img.shape == result["red"].image.shape
    for stem, first in (("rgb", "red"), ("false_colour", "nir")):
        png = Image.open(paths[stem])
        assert png.mode == "RGB" and png.size == (14, 12)
        lo, hi = np.percentile(result[first].image, PREVIEW_STRETCH_PCT)
        want = np.round(np.clip((result[first].image - lo) * 255.0 / (hi - lo), 0, 255))
        np.testing.assert_array_equal(np.asarray(png)[..., 0], want.astype(np.uint8))


def test_bad_input_is_one_line(pms):
    scene = Scene(19.6, 19.6)
    with pytest.raises(ConfigError, match="band = 'swir'"):
        simulate_bands(scene, pms, pixel_m=0.245, bands=["swir"])
    with pytest.raises(ConfigError, match="smaller than one pixel"):
        simulate_bands(scene, pms, pixel_m=0.245, window=(0, 0, 4, 4))
    with pytest.raises(ConfigError, match="units"):
        simulate_bands(scene, pms, pixel_m=0.245, units="photons")


def test_previews_found_by_wavelength_when_names_differ(pms, tmp_path):
    """MS bands named b1..b4: the previews take them by centre wavelength (blue, green, red, NIR ranges)."""
    names = ["pan", "b1", "b2", "b3", "b4"]
    system = pms.model_copy(update={"bands": tuple(b.model_copy(update={"name": n})
                                                   for b, n in zip(pms.bands, names, strict=True))})  # fmt: skip
    result = simulate_bands(Scene(15.68, 15.68, background=0.3), system, pixel_m=0.245, noise=True, seed=4)
    paths = write_band_rasters(result, tmp_path)
    assert sorted(paths) == ["false_colour", "ms", "pan", "rgb"]
    from PIL import Image

    fc = np.asarray(Image.open(paths["false_colour"]))
    lo, hi = np.percentile(result["b4"].image, PREVIEW_STRETCH_PCT)  # NIR (830 nm) in the red channel
    want = np.round(np.clip((result["b4"].image - lo) * 255.0 / (hi - lo), 0, 255)).astype(np.uint8)
    np.testing.assert_array_equal(fc[..., 0], want)
