"""Spectral materials: the packaged library, PROSAIL vegetation, band averages and spectral scene items.

Physical sanity checks follow the literature, never numbers produced by the code under test: vegetation's red edge
and green peak (e.g. Jacquemoud et al. 2009), water dark in the NIR, a black pigment below 0.1, titanium dioxide's
absorption edge at 0.41 um (its USGS record), asphalt dark and rising slowly with wavelength (Herold et al. 2004).
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain.errors import ConfigError
from satchain.scene import layout_from_dict, layout_to_dict, load_layout
from satchain.scene.materials import (
    DEFAULT_BAND_M,
    Material,
    band_reflectance,
    material,
    materials,
    read_spectrum,
    vegetation,
)
from satchain.scene.spectral import MATERIAL_SLOTS, MaterialSlot, layout_for_band

NM = 1e-9
PACKAGED = [n for n in materials() if n != "green_vegetation"]


def at(m: Material, nm: float) -> float:
    return float(np.interp(nm * NM, m.wavelengths_m, m.reflectance))


def mean_over(m: Material, lo_nm: float, hi_nm: float) -> float:
    lam = np.linspace(lo_nm, hi_nm, 201) * NM
    return float(np.mean(np.interp(lam, m.wavelengths_m, m.reflectance)))


def flat_band(lo_nm, hi_nm, n=101):
    lam = np.linspace(lo_nm, hi_nm, n) * NM
    return lam, np.ones_like(lam)


@pytest.fixture(scope="module")
def veg():
    return vegetation()


# ---------------------------------------------------------------------------------------------- the library


def test_library_has_the_issue_materials():
    names = set(materials())
    assert len(names) >= 8
    for needed in ("green_vegetation", "dry_grass", "asphalt", "concrete", "water", "white_paint", "black_paint"):
        assert needed in names
    assert names & {"roof_shingle", "galvanized_metal", "red_brick"}


@pytest.mark.parametrize("name", materials())
def test_every_material_covers_400_1000_nm_in_0_1_finite_with_a_source(name):
    m = material(name)
    lo, hi = m.range_m
    assert lo <= 400 * NM and hi >= 1000 * NM
    assert np.all(np.isfinite(m.reflectance)) and m.reflectance.min() >= 0 and m.reflectance.max() <= 1
    assert np.all(np.diff(m.wavelengths_m) > 0)
    assert len(m.source) > 20
    assert not m.reflectance.flags.writeable


@pytest.mark.parametrize("name", PACKAGED)
def test_packaged_files_name_their_record_and_licence(name):
    m = material(name)
    assert "USGS Spectral Library Version 7" in m.source
    assert "Record=" in m.source and "public domain" in m.source
    assert m.range_m == pytest.approx((350 * NM, 2500 * NM))
    assert np.allclose(np.diff(m.wavelengths_m), 5 * NM)


def test_green_vegetation_red_edge_and_green_peak(veg):
    assert material("green_vegetation") == veg
    assert at(veg, 800) > 3 * at(veg, 670)  # the red edge
    lam = np.arange(500, 601) * NM
    peak_nm = lam[np.argmax(np.interp(lam, veg.wavelengths_m, veg.reflectance))] / NM
    assert 530 <= peak_nm <= 570  # the green peak (chlorophyll absorbs at 450 and 670 nm)
    assert at(veg, 550) > at(veg, 500) and at(veg, 550) > at(veg, 670)


def test_water_is_dark_in_the_nir():
    w = material("water")
    assert w.reflectance[(w.wavelengths_m >= 700 * NM) & (w.wavelengths_m <= 1000 * NM)].max() < 0.1
    assert at(w, 450) > at(w, 850)  # water absorbs more in the NIR than in the blue


def test_paints_and_white_reference():
    black = material("black_paint")
    sel = (black.wavelengths_m >= 400 * NM) & (black.wavelengths_m <= 1000 * NM)
    assert black.reflectance[sel].max() < 0.1
    ref = material("white_reference")  # Spectralon: ~0.99 flat
    assert ref.reflectance[sel].min() > 0.8
    tio2 = material("white_paint")  # TiO2 pigment: bright above its 0.41 um absorption edge, dark below
    assert tio2.reflectance[(tio2.wavelengths_m >= 450 * NM) & (tio2.wavelengths_m <= 1000 * NM)].min() > 0.5
    assert at(tio2, 380) < 0.2 < 0.5 * at(tio2, 550)
    assert mean_over(tio2, 450, 1000) > 10 * mean_over(black, 450, 1000)


def test_asphalt_dark_and_rising_slowly():
    a = material("asphalt")
    assert mean_over(a, 400, 1000) < 0.2
    lam = np.arange(400, 1001, 50) * NM
    r = np.interp(lam, a.wavelengths_m, a.reflectance)
    assert np.all(np.diff(r) > 0)  # rises monotonically (at 50 nm steps) ...
    assert r[-1] < 3 * r[0]  # ... but slowly


def test_dry_grass_has_no_red_edge_like_green_vegetation(veg):
    g = material("dry_grass")
    assert at(g, 800) / at(g, 670) < 0.5 * at(veg, 800) / at(veg, 670)
    assert at(g, 670) > at(veg, 670)  # no chlorophyll absorption


# ----------------------------------------------------------------------------------------------- PROSAIL


def test_more_chlorophyll_lowers_green_and_red(veg):
    rich = vegetation(cab_ug_per_cm2=80.0)
    poor = vegetation(cab_ug_per_cm2=15.0)
    for nm in (550, 670):
        assert at(rich, nm) < at(veg, nm) < at(poor, nm)


def test_more_lai_raises_the_nir():
    """Leaves scatter the NIR back more than a dark (wet) soil: NIR reflectance grows with LAI towards the
    infinite-canopy value, and the red falls as more leaves cover the soil."""
    canopies = [vegetation(lai=lai, soil_dry_fraction=0.0) for lai in (0.5, 1.0, 2.0, 4.0, 8.0)]
    assert np.all(np.diff([at(v, 850) for v in canopies]) > 0)
    assert np.all(np.diff([at(v, 670) for v in canopies]) < 0)


def test_vegetation_names_its_parameters_and_refuses_bad_ones():
    v = vegetation(lai=5.0, cab_ug_per_cm2=30.0)
    assert v.name == "vegetation(cab_ug_per_cm2=30, lai=5)"
    assert "lai=5" in v.source and "PROSAIL" in v.source
    with pytest.raises(ConfigError, match=r"vegetation.lai = 20.*\[0, 10\]"):
        vegetation(lai=20.0)
    with pytest.raises(ConfigError, match="unknown parameter.*'chlorophyll'"):
        vegetation(chlorophyll=40.0)


# -------------------------------------------------------------------------------------- band reflectance


@settings(max_examples=60, deadline=None)
@given(
    value=st.floats(0.0, 1.0),
    centre_nm=st.floats(420.0, 980.0),
    fwhm_nm=st.floats(1.0, 300.0),
    n=st.integers(2, 400),
)
def test_band_reflectance_of_a_flat_spectrum_is_its_value(value, centre_nm, fwhm_nm, n):
    lam = np.linspace(centre_nm - fwhm_nm, centre_nm + fwhm_nm, n) * NM
    s = np.exp(-4 * np.log(2) * ((lam - centre_nm * NM) / (fwhm_nm * NM)) ** 2)
    assert band_reflectance(value, lam, s) == value  # a grey value: exactly
    lam_m = np.array([100.0, 777.0, 1500.0]) * NM
    flat = Material("flat", lam_m, np.full(3, value), source="flat test spectrum")
    assert band_reflectance(flat, lam, s) == pytest.approx(value, abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    a=st.floats(0.0, 0.3),
    slope_per_um=st.floats(-0.3, 0.3),
    centre_nm=st.floats(500.0, 900.0),
    fwhm_nm=st.floats(5.0, 120.0),
)
def test_linear_spectrum_gaussian_response_gives_the_centre_value(a, slope_per_um, centre_nm, fwhm_nm):
    """A symmetric response over a linear R(lam) averages to R(centre): integral (a + b lam) S / integral S."""
    lam_m = np.linspace(100, 1600, 301) * NM  # the material's own (5 nm) grid, unrelated to the band's
    r = 0.4 + a + slope_per_um * (lam_m / 1e-6 - 0.7)
    m = Material("linear", lam_m, r, source="linear test spectrum")
    half = 3 * fwhm_nm
    lam = np.linspace(centre_nm - half, centre_nm + half, 301) * NM
    s = np.exp(-4 * np.log(2) * ((lam - centre_nm * NM) / (fwhm_nm * NM)) ** 2)
    expected = 0.4 + a + slope_per_um * (centre_nm * NM / 1e-6 - 0.7)
    assert band_reflectance(m, lam, s) == pytest.approx(expected, abs=1e-12)


def test_band_reflectance_of_a_boxcar_is_the_mean_of_the_spectrum():
    lam_m = np.arange(400, 1001, 10) * NM
    r = 0.1 + 0.5 * ((lam_m / NM - 400) / 600) ** 2  # a parabola: mean over [a, b] has a closed form
    m = Material("parabola", lam_m, r, source="test")
    lam, s = flat_band(500, 700, 2001)
    x0, x1 = (500 - 400) / 600, (700 - 400) / 600
    exact = 0.1 + 0.5 * (x1**3 - x0**3) / (3 * (x1 - x0))
    # the spectrum is its 10 nm chords: on average above the parabola by f'' h^2 / 12
    chords = 0.5 * 2 / 600**2 * 10**2 / 12
    assert band_reflectance(m, lam, s) == pytest.approx(exact + chords, abs=1e-12)


def test_unknown_material_lists_the_library():
    with pytest.raises(ConfigError) as e:
        material("asfalt")
    msg = str(e.value)
    assert "'asfalt'" in msg and "\n" not in msg
    for name in materials():
        assert name in msg


def test_response_outside_the_material_range_is_refused(veg):
    lam, s = flat_band(380, 450)
    with pytest.raises(
        ConfigError, match=r"band 380.0-450.0 nm reaches outside material 'green_vegetation'.*400.0-2500.0 nm"
    ):
        band_reflectance(veg, lam, s)
    lam, s = flat_band(2400, 2600)
    with pytest.raises(ConfigError, match="2600.0 nm reaches outside material 'asphalt'"):
        band_reflectance(material("asphalt"), lam, s)
    # zero response samples outside the range do not count
    lam = np.array([300, 399, 450, 500, 501, 3000]) * NM
    assert 0 < band_reflectance(veg, lam, np.array([0, 0, 1, 1, 0, 0.0])) < 1


@pytest.mark.parametrize(
    "lam_nm, s, match",
    [
        ([500, 600, 550], [1, 1, 1], "strictly increasing"),
        ([500, 600], [1, -1], ">= 0"),
        ([500, 600], [0, 0], "zero everywhere"),
        ([500], [1], "same length"),
    ],
)
def test_bad_responses_are_refused(lam_nm, s, match):
    with pytest.raises(ConfigError, match=match):
        band_reflectance(material("concrete"), np.array(lam_nm) * NM, np.array(s, dtype=float))


def test_spectrum_file_round_trip_and_bad_table(tmp_path):
    f = tmp_path / "paint.csv"
    f.write_text("# my paint, lab 2024\nwavelength_nm,reflectance\n400,0.5\n700,0.6\n1000,0.7\n")
    m = read_spectrum(f)
    assert m.name == "paint" and "my paint" in m.source
    lam, s = flat_band(400, 1000)
    assert band_reflectance(m, lam, s) == pytest.approx(0.6, abs=1e-12)
    bad = tmp_path / "bad.csv"
    bad.write_text("wavelength_nm,reflectance\n400,0.5\n700,0.6\n650,0.7\n")
    with pytest.raises(ConfigError, match="strictly increasing; sample 2 \\(650.0\\) follows 700.0"):
        read_spectrum(bad)
    over = tmp_path / "over.csv"
    over.write_text("400,0.5\n700,1.6\n")
    with pytest.raises(ConfigError, match=r"reflectance: must be in \[0, 1\]"):
        read_spectrum(over)


# ----------------------------------------------------------------------------------------- spectral scenes

SCENE = {
    "scene": {"width_m": 60.0, "height_m": 40.0, "background_material": "dry_grass", "pixel_m": 0.5},
    "items": [
        {"kind": "slanted_edge", "id": "edge", "center_m": [15.0, 20.0], "size_m": 20.0,
         "bright_material": "white_paint", "dark_material": "black_paint"},
        {"kind": "road", "id": "road", "origin_m": [32.0, 10.0], "length_m": 25.0, "asphalt_material": "asphalt"},
        {"kind": "siemens_star", "id": "star", "center_m": [45.0, 28.0], "radius_m": 8.0,
         "bright_material": "concrete", "dark_material": "asphalt"},
    ],
}  # fmt: skip


def test_layout_with_materials_loads_and_its_band_layout_has_band_greys():
    sc = layout_from_dict(SCENE)
    assert {(s.item_id, s.slot) for s in sc.materials} == {
        (None, "background"), ("edge", "bright"), ("edge", "dark"), ("road", "asphalt"),
        ("star", "bright"), ("star", "dark"),
    }  # fmt: skip
    lam, s = flat_band(760, 900)
    band = layout_for_band(sc, lam, s)
    assert band.materials == ()
    mean = {n: mean_over(material(n), 760, 900) for n in ("dry_grass", "white_paint", "black_paint", "asphalt")}
    mean["concrete"] = mean_over(material("concrete"), 760, 900)
    edge, road, star = band.items
    assert band.background == pytest.approx(mean["dry_grass"], abs=2e-3)
    assert edge.bright == pytest.approx(mean["white_paint"], abs=2e-3)
    assert edge.dark == pytest.approx(mean["black_paint"], abs=2e-3)
    assert road.asphalt == pytest.approx(mean["asphalt"], abs=2e-3)
    assert star.mean + star.amplitude == pytest.approx(mean["concrete"], abs=2e-3)
    assert star.mean - star.amplitude == pytest.approx(mean["asphalt"], abs=2e-3)
    # other slots keep their grey values; geometry unchanged
    assert road.white == sc.items[1].white and edge.center_m == sc.items[0].center_m
    # rendering the band layout: the edge's bright side reads the band's white paint
    img = band.render(pixel_m=0.5)
    assert img[40, 44] == pytest.approx(edge.bright, abs=1e-6)  # x 22-22.5 m, y 20-20.5 m: the bright side
    assert img[40, 16] == pytest.approx(edge.dark, abs=1e-6)  # x 8-8.5 m: the dark side
    assert img[2, 2] == pytest.approx(band.background, abs=1e-6)


def test_scene_renders_materials_over_the_default_band_without_one():
    sc = layout_from_dict(SCENE)
    lam, s = flat_band(DEFAULT_BAND_M[0] / NM, DEFAULT_BAND_M[1] / NM)
    assert sc.background == pytest.approx(band_reflectance(material("dry_grass"), lam, s), abs=1e-9)
    assert sc.items[0].bright == pytest.approx(band_reflectance(material("white_paint"), lam, s), abs=1e-9)


def test_a_layout_without_materials_is_unchanged_and_renders_identically():
    d = json.loads(json.dumps(SCENE))
    d["scene"].pop("background_material")
    d["scene"]["background"] = 0.2
    for it in d["items"]:
        for k in [k for k in it if k.endswith("_material")]:
            it.pop(k)
    grey = layout_from_dict(d)
    lam, s = flat_band(450, 520)
    out = layout_for_band(grey, lam, s)
    assert out is grey
    np.testing.assert_array_equal(out.render(pixel_m=0.5), layout_from_dict(d).render(pixel_m=0.5))
    # a grey scene's truth has no materials entry (unchanged from before)
    assert "materials" not in grey.truth()


def test_materials_round_trip_through_dict_and_file(tmp_path):
    sc = layout_from_dict(SCENE)
    d = layout_to_dict(sc)
    assert d["scene"]["background_material"] == "dry_grass" and "background" not in d["scene"]
    assert d["items"][0]["bright_material"] == "white_paint" and "bright" not in d["items"][0]
    assert "mean" not in d["items"][2] and d["items"][2]["dark_material"] == "asphalt"
    again = layout_from_dict(d)
    assert again == sc
    truth = sc.truth()
    assert {m["material"] for m in truth["materials"]} >= {"white_paint", "dry_grass"}


def test_spectrum_file_in_a_scene_file_is_relative_to_it(tmp_path):
    (tmp_path / "spectra").mkdir()
    (tmp_path / "spectra" / "panel.csv").write_text("400,0.3\n1000,0.5\n")
    (tmp_path / "s.toml").write_text(
        '[scene]\nwidth_m = 20.0\nheight_m = 20.0\n\n[[items]]\nkind = "slanted_edge"\nid = "e"\n'
        'center_m = [10.0, 10.0]\nsize_m = 10.0\nbright_material = "spectra/panel.csv"\n'
    )
    sc = load_layout(tmp_path / "s.toml")
    lam, s = flat_band(500, 600)
    assert layout_for_band(sc, lam, s).items[0].bright == pytest.approx(0.3 + 0.2 * 150 / 600, abs=1e-12)


@pytest.mark.parametrize(
    "patch, match",
    [
        ({"bright_material": "asfalt"}, "bright_material = 'asfalt': not in the material library; known: asphalt, "),
        ({"bright_material": "asphalt", "bright": 0.7}, "bright = 0.7 and bright_material = 'asphalt': give one"),
        ({"roof_material": "asphalt"}, "unknown key 'roof_material'; material keys allowed here: bright_material"),
        ({"bright_material": "missing.csv"}, "no such file"),
    ],
)
def test_bad_material_keys_are_one_line_errors(patch, match):
    d = json.loads(json.dumps(SCENE))
    d["items"][0].update(patch)
    with pytest.raises(ConfigError, match=match) as e:
        layout_from_dict(d)
    assert "\n" not in str(e.value)


def test_star_needs_both_materials_and_bright_above_dark():
    d = json.loads(json.dumps(SCENE))
    d["items"][2].pop("dark_material")
    with pytest.raises(ConfigError, match="bright_material and dark_material together"):
        layout_from_dict(d)
    d["items"][2]["bright_material"], d["items"][2]["dark_material"] = "black_paint", "white_paint"
    with pytest.raises(ConfigError, match="bright reflectance .* < dark"):
        layout_from_dict(d)


def test_band_outside_a_scene_material_is_refused():
    sc = layout_from_dict(SCENE)
    lam, s = flat_band(300, 360)  # the packaged spectra start at 350 nm
    with pytest.raises(ConfigError, match="band 300.0-360.0 nm reaches outside material"):
        layout_for_band(sc, lam, s)


def test_every_slot_names_a_grey_field_of_its_kind():
    from satchain.scene.layout import ITEM_KINDS

    for kind, slots in MATERIAL_SLOTS.items():
        fields = {f.name for f in dataclasses.fields(ITEM_KINDS[kind])}
        expected = {"mean", "amplitude"} if kind == "siemens_star" else set(slots)
        assert expected <= fields, kind
    python_api = MaterialSlot("e", "bright", material("white_reference"))
    assert python_api.key == "white_reference"


def test_cli_unknown_material_exits_2(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('[scene]\nwidth_m = 20.0\nheight_m = 20.0\nbackground_material = "lava"\n')
    out = tmp_path / "x.tif"
    r = subprocess.run(
        [sys.executable, "-m", "satchain", "scene", "--layout", str(f), "-o", str(out)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert r.returncode == 2, r.stderr
    assert "background_material = 'lava': not in the material library; known: asphalt" in r.stderr


def test_a_response_with_a_sliver_outside_the_range_is_integrated_more_is_refused():
    """A measured response's noise floor outside a material's range (the default Bayer red's 0.2 % of peak at
    380-395 nm against PROSAIL's 400 nm start) is integrated with the spectrum's end value; a band with more than
    0.1 % of its response outside is refused, naming both ranges."""
    from satchain.scene.materials import OUTSIDE_WEIGHT, band_reflectance, material

    veg = material("green_vegetation")
    lam = np.arange(380e-9, 781e-9, 5e-9)
    response = np.exp(-0.5 * ((lam - 600e-9) / 40e-9) ** 2)
    response[lam < 400e-9] = 0.002  # the sliver: 4 samples at 0.2 % of the peak
    inside = lam >= 400e-9
    got = band_reflectance(veg, lam, response)
    ref = band_reflectance(veg, lam[inside], response[inside])
    assert abs(got - ref) < OUTSIDE_WEIGHT  # at most the sliver's share of the reflectance range
    wide = np.exp(-0.5 * ((lam - 450e-9) / 40e-9) ** 2)  # ~8 % of it below 400 nm
    with pytest.raises(ConfigError, match=r"reaches outside material 'green_vegetation'.*400.0-2500.0 nm"):
        band_reflectance(veg, lam, wide)
