"""A multiband reflectance cube as the ground truth of a banded system (satchain.engine.cube; issue 32 point 1).

Cubes are written here (rasterio; float32 and uint16 reflectance x 10000 with the file's scale, georeferenced in
UTM), their bands' centre wavelengths in each of the forms a file may state them. Each system band's ground truth
is checked against closed forms computed here: a flat spectrum gives its grey value (the weights sum to 1), a
linear one ``a + b (lam - lam0)`` gives ``a + b (lam_b - lam0)`` with ``lam_b`` the band's response-weighted mean
wavelength (integrated here on a fine grid), a cube of library spectra sampled at its centres gives each
material's band reflectance within the linear interpolation's error (at 5 nm, the USGS spectra's own grid: exact;
at 10 nm, every material including PROSAIL vegetation within 3e-4, measured 2.1e-4). Then the refusals (one line,
exit 2 on the CLI) and ``satchain simulate CUBE --preset ankarasat3-pms -o DIR``: pan.tif and ms.tif as for scenes,
with the cube's CRS and origin.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS
from typer.testing import CliRunner

from satchain import load_preset
from satchain.cli.main import app
from satchain.engine.bands import band_response
from satchain.engine.cube import ReflectanceCube, cube_wavelengths_m, simulate_cube
from satchain.errors import ConfigError
from satchain.scene.materials import band_reflectance, material, materials

runner = CliRunner()
SYSTEM = load_preset("ankarasat3-pms")
TRANSFORM = Affine(0.49, 0.0, 500000.0, 0.0, -0.49, 4400000.0)  # UTM 36N, the PAN GSD
CRS_UTM = CRS.from_epsg(32636)


def _write(path: Path, cube: np.ndarray, lam_nm, *, how: str = "band", dtype: str = "float32", scale=None) -> Path:
    """``cube`` (bands, rows, cols) as a GeoTIFF whose bands state ``lam_nm`` by ``how``: "band" (GDAL band
    metadata wavelength + wavelength_units, ENVI-style), "imagery" (IMAGERY CENTRAL_WAVELENGTH_UM), "json"
    (satchain's description), or "none"."""
    import json

    k, h, w = cube.shape
    with rasterio.open(path, "w", driver="GTiff", width=w, height=h, count=k, dtype=dtype, transform=TRANSFORM,
                       crs=CRS_UTM) as d:  # fmt: skip
        d.write(cube.astype(dtype))
        if scale is not None:
            d.scales = [scale] * k
        for i, v in enumerate(lam_nm, start=1):
            if how == "band":
                d.update_tags(i, wavelength=f"{v:g}", wavelength_units="Nanometers")
            elif how == "imagery":
                d.update_tags(i, ns="IMAGERY", CENTRAL_WAVELENGTH_UM=f"{v / 1000:.6g}")
        if how == "json":
            d.update_tags(TIFFTAG_IMAGEDESCRIPTION=json.dumps({"satchain": {"wavelengths_nm": list(lam_nm)}}))
    return path


def _bands(path: Path, **kw) -> list[np.ndarray]:
    """Every system band's ground truth from the cube, at the cube's pixels."""
    with ReflectanceCube(path, **kw) as c:
        return [c.band_scene(SYSTEM, i).render() for i in range(len(SYSTEM.bands))]


LAM_NM = np.arange(400.0, 1000.1, 50.0)  # 13 bands over every band of the preset (PAN 450-900 nm)


@pytest.mark.parametrize("how", ["band", "imagery", "json"])
def test_a_flat_spectrum_gives_every_band_its_grey_value(tmp_path, how):
    """float32, wavelengths stated three ways: every band's image is the pixel's grey value (to rounding)."""
    grey = np.random.default_rng(1).uniform(0.02, 0.95, (12, 10))
    p = _write(tmp_path / "flat.tif", np.broadcast_to(grey, (LAM_NM.size, 12, 10)), LAM_NM, how=how)
    want = grey.astype(np.float32).astype(np.float64)
    for img in _bands(p):
        assert np.abs(img - want).max() < 1e-12


def test_uint16_scaled_reflectance_flat_and_linear(tmp_path):
    """uint16 reflectance x 10000 (the file's scale 1e-4): a flat spectrum is its value exactly (to rounding); a
    linear spectrum ``a + b (lam - 700 nm)`` gives ``a + b (lam_b - 700 nm)``, ``lam_b`` the band's weighted mean
    wavelength integrated here on a 1e5-point grid."""
    rng = np.random.default_rng(2)
    a, b = rng.uniform(0.3, 0.6, (9, 11)), rng.uniform(-4e5, 4e5, (9, 11))  # b: reflectance per metre
    lin = a + b * (LAM_NM[:, None, None] * 1e-9 - 700e-9)
    stored = np.round(lin * 10000).astype(np.uint16)
    p = _write(tmp_path / "lin.tif", stored, LAM_NM, dtype="uint16", scale=1e-4)
    got = _bands(p)
    for i, img in enumerate(got):
        lam, s = band_response(SYSTEM, i)
        fine = np.linspace(lam[0], lam[-1], 100001)
        sf = np.interp(fine, lam, s)
        mean_lam = np.trapezoid(fine * sf, fine) / np.trapezoid(sf, fine)
        # the stored values' rounding (5e-5) is linear in them too: compare with the stored cube's own line
        a_s = stored[6] * 1e-4  # band 7 = 700 nm
        b_s = (stored[8] * 1e-4 - stored[4] * 1e-4) / 200e-9  # its slope from 600 and 800 nm
        want = a + b * (mean_lam - 700e-9)
        assert np.abs(img - want).max() < 1.5e-4  # the file's 1e-4 steps
        if SYSTEM.band_names[i] != "pan":  # MS bands: 600-800 nm slope of the stored values, centre at 700
            assert np.abs(img - (a_s + b_s * (mean_lam - 700e-9))).max() < 2e-4
    flat = np.full((LAM_NM.size, 9, 11), 4321, np.uint16)
    for img in _bands(_write(tmp_path / "flat16.tif", flat, LAM_NM, dtype="uint16", scale=1e-4)):
        assert np.abs(img - 0.4321).max() < 1e-12


@pytest.mark.parametrize(("step_nm", "tol"), [(5.0, 1e-9), (10.0, 3e-4)])
def test_library_spectra_sampled_at_the_centres_reproduce_band_reflectance(tmp_path, step_nm, tol):
    """Each cube column a library material's spectrum sampled at the centres: every band within ``tol`` of
    :func:`band_reflectance` of the material (at 5 nm the USGS spectra's own samples, so exact; PROSAIL
    vegetation, at 1 nm, is left to the 10 nm case, which holds every material)."""
    names = [m for m in materials() if step_nm > 5 or m != "green_vegetation"]
    lam = np.arange(400.0, 1000.1, step_nm)
    mats = [material(m) for m in names]
    spectra = np.stack([np.interp(lam * 1e-9, m.wavelengths_m, m.reflectance) for m in mats], axis=1)
    cube = np.repeat(spectra[:, None, :], 8, axis=1)  # (bands, 8 rows, one column per material)
    p = _write(tmp_path / "lib.tif", np.repeat(cube, 1, axis=2), lam, how="imagery", dtype="float64")
    for i, img in enumerate(_bands(p)):
        want = np.array([band_reflectance(m, *band_response(SYSTEM, i)) for m in mats])
        assert np.abs(img - want[None, :]).max() < tol, (SYSTEM.band_names[i], np.abs(img[0] - want).max())


def test_refusals(tmp_path):
    """No wavelengths, wavelengths not increasing, a count that is not the bands', a band reaching outside."""
    cube = np.full((4, 10, 10), 0.3, np.float32)
    bare = _write(tmp_path / "bare.tif", cube, [490, 560, 665, 842], how="none")
    with pytest.raises(ConfigError, match="centre wavelength"):
        cube_wavelengths_m(bare)
    bad = _write(tmp_path / "bad.tif", cube, [490, 560, 560, 842])
    with pytest.raises(ConfigError, match="strictly increasing.*band 3"):
        cube_wavelengths_m(bad)
    with pytest.raises(ConfigError, match="4 bands"):
        cube_wavelengths_m(bare, wavelengths_nm=[490, 560, 665])
    narrow = _write(tmp_path / "narrow.tif", cube, [490, 560, 665, 842])  # PAN reaches 450 nm, NIR 900
    with pytest.raises(ConfigError, match="reaches outside the cube's 490.0-842.0 nm"):
        _bands(narrow)
    wide = _write(tmp_path / "wide.tif", cube, [400, 560, 665, 1000])
    assert all(np.allclose(b, 0.3, atol=1e-7) for b in _bands(wide))
    for args, words in (([str(bare), "--wavelengths-nm", "490,560,842,665"], "--wavelengths-nm: wavelengths must be "
                         "strictly increasing"), ([str(narrow)], "reaches outside the cube"),
                        ([str(bare), "--wavelengths-nm", "490,560"], "2 wavelengths for the 4 bands")):  # fmt: skip
        r = runner.invoke(app, ["simulate", *args, "--preset", "ankarasat3-pms", "-o", str(tmp_path / "o")])
        assert r.exit_code == 2, r.output
        assert words in " ".join(r.output.split()), r.output
    r = runner.invoke(app, ["simulate", str(bare), "--preset", "ankarasat3", "--wavelengths-nm", "1,2,3,4", "-o",
                            str(tmp_path / "o.tif")])  # fmt: skip
    assert r.exit_code == 2 and "applies to a banded system" in " ".join(r.output.split()), r.output


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    """``satchain simulate cube.tif --preset ankarasat3-pms -o DIR``, noise-free in reflectance: a uniform grey
    cube with a bright square, wavelengths from --wavelengths-nm."""
    d = tmp_path_factory.mktemp("cube")
    img = np.full((64, 64), 0.25)
    img[20:44, 20:44] = 0.6
    p = _write(d / "cube.tif", np.broadcast_to(img, (4, 64, 64)), [400, 560, 665, 1000], how="none")
    out = d / "out"
    r = runner.invoke(app, ["simulate", str(p), "--preset", "ankarasat3-pms", "--wavelengths-nm", "400,560,665,1000",
                            "--units", "reflectance", "--no-noise", "-o", str(out)])  # fmt: skip
    return r, out


def test_cli_writes_pan_and_ms_georeferenced_as_the_cube(cli_run):
    r, out = cli_run
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in out.iterdir()) == ["false_colour.png", "ms.tif", "pan.tif", "rgb.png"]
    with rasterio.open(out / "pan.tif") as pan, rasterio.open(out / "ms.tif") as ms:
        assert pan.crs == CRS_UTM and ms.crs == CRS_UTM
        assert pan.transform.almost_equals(TRANSFORM) and ms.transform.almost_equals(TRANSFORM @ Affine.scale(4))
        assert ms.descriptions == ("blue", "green", "red", "nir") and (ms.height, ms.width) == (16, 16)
        a, m = pan.read(1), ms.read()
    # the grey values through the chain, where they lie (the square blurred by the system's PSF: its far tails
    # reach 1e-3 of the step at the corner, its centre keeps 97 % of the step in PAN)
    assert abs(float(a[:4, :4].mean()) - 0.25) < 2e-3 and 0.25 + 0.97 * 0.35 < float(a[30:34, 30:34].mean()) < 0.6
    assert np.all(m[:, 7:9, 7:9] > 0.45) and np.all(np.abs(m[:, 0, 0] - 0.25) < 0.01)
    assert np.unravel_index(np.argmax(a), a.shape) in [(r, c) for r in (31, 32) for c in (31, 32)]


def test_simulate_cube_api_matches_the_cli(cli_run, tmp_path):
    """The API (:func:`simulate_cube`) forms the bands the CLI wrote."""
    r, out = cli_run
    with rasterio.open(out / "ms.tif") as ms:
        m = ms.read()
    cube = out.parent / "cube.tif"
    res = simulate_cube(cube, SYSTEM, wavelengths_nm=[400, 560, 665, 1000], noise=False, bands=["red"])
    assert res.names == ("red",)
    assert np.allclose(res["red"].image, m[2], atol=1e-6)


def test_a_linear_float_spectrum_gives_the_band_weighted_mean_wavelength_exactly(tmp_path):
    """float64 ``a + b (lam - 700 nm)`` per pixel: ``a + b (lam_b - 700 nm)`` to 1e-12 (linear interpolation of
    a line is the line; measured 2e-16)."""
    rng = np.random.default_rng(3)
    a, b = rng.uniform(0.3, 0.6, (8, 9)), rng.uniform(-4e5, 4e5, (8, 9))
    p = _write(tmp_path / "linf.tif", a + b * (LAM_NM[:, None, None] * 1e-9 - 700e-9), LAM_NM, dtype="float64")
    for i, img in enumerate(_bands(p)):
        lam, s = band_response(SYSTEM, i)
        fine = np.linspace(lam[0], lam[-1], 200001)
        sf = np.interp(fine, lam, s)
        mean_lam = np.trapezoid(fine * sf, fine) / np.trapezoid(sf, fine)
        assert np.abs(img - (a + b * (mean_lam - 700e-9))).max() < 1e-12


@pytest.fixture(scope="module")
def texture_cube(tmp_path_factory) -> Path:
    """A smooth random texture (0.1-0.7, features ~2 px), flat in wavelength: 160 x 160 PAN px, 40 x 40 MS px."""
    from scipy import ndimage

    img = ndimage.gaussian_filter(np.random.default_rng(3).random((160, 160)), 2.0)
    img = 0.1 + 0.6 * (img - img.min()) / (img.max() - img.min())
    return _write(tmp_path_factory.mktemp("tex") / "tex.tif", np.broadcast_to(img, (4, 160, 160)),
                  [400, 560, 665, 1000], how="none")  # fmt: skip


def _blue_from_pan(cube: Path, system) -> tuple[float, float]:
    from satchain.measure.registration import measure_registration

    r = simulate_cube(cube, system, wavelengths_nm=[400, 560, 665, 1000], noise=False, bands=["pan", "blue"])
    return measure_registration(r["pan"].image[16:144, 16:144], r["blue"].image[4:36, 4:36], scale=4).offset_px


@pytest.mark.parametrize("error", [2e-3, -3e-3])
def test_a_cube_under_a_line_rate_error_misregisters_its_bands_as_budgeted(texture_cube, error):
    """motion.line_rate_error with a cube (its bands' grids displaced up to a pixel beyond it, where the engine
    continues it by its border rule, without a warning below a whole pixel): blue's offset from PAN moves by the
    budget's line_rate offset (-0.51 / +0.77 px) within 0.02 px (measured: within 0.0005)."""
    from satchain.prediction.budget import band_budgets

    base = _blue_from_pan(texture_cube, SYSTEM)
    system = SYSTEM.replace({"motion.line_rate_error": error})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = _blue_from_pan(texture_cube, system)
    want = [b for b in band_budgets(system) if b["name"] == "blue"][0]["registration"]["line_rate"]
    assert got[0] - base[0] == pytest.approx(want["alt_px"], abs=0.02)
    assert got[1] - base[1] == pytest.approx(want["act_px"], abs=0.02)


def test_a_cube_under_the_earths_rotation_warns_where_its_bands_see_beyond_it(texture_cube):
    """The Earth's rotation moves the MS grids 13-23 px across track over their delays: beyond a 40-pixel cube for
    every MS band, which the engine continues by its border rule (it was refused with 'outside the cube') and says
    so, band by band."""
    from satchain.errors import SatchainWarning

    system = SYSTEM.replace({"orbit.earth_rotation": True, "orbit.latitude_deg": 40.0, "orbit.inclination_deg": 97.7})
    with pytest.warns(SatchainWarning) as caught:
        r = simulate_cube(texture_cube, system, wavelengths_nm=[400, 560, 665, 1000], noise=False)
    said = " ".join(str(w.message) for w in caught)
    for name in ("blue", "green", "red", "nir"):
        assert f"band {name!r}" in said
        assert np.isfinite(r[name].image).all() and r[name].image.shape == (40, 40)
    assert "band 'pan'" not in said and "border = 'symmetric'" in said
