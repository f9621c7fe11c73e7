"""`satchain simulate` of georeferenced rasters written here with rasterio: every band through the chain, the
input's CRS and origin kept at the GSD, nodata where a pitch cell touches invalid input, a Cloud-Optimized GeoTIFF;
and `satchain.simulate_image`, the same in memory."""

from __future__ import annotations

import math

import numpy as np
import pytest
import rasterio
from rasterio import Affine
from typer.testing import CliRunner

import satchain
from satchain import load_preset
from satchain.cli.main import app
from satchain.engine import georaster
from satchain.engine.files import simulate_file
from satchain.errors import ConfigError

SYSTEM = load_preset("ankarasat3")
GSD = SYSTEM.gsd_act_m  # 0.49 m
runner = CliRunner()


def _write(path, data, *, transform, crs="EPSG:32636", nodata=None, driver="GTiff", **kw):
    data = np.asarray(data)
    data = data[None] if data.ndim == 2 else data
    prof = dict(driver=driver, width=data.shape[2], height=data.shape[1], count=data.shape[0], dtype=data.dtype.name,
                crs=crs, transform=transform, nodata=nodata, **kw)  # fmt: skip
    with rasterio.open(path, "w", **prof) as d:
        d.write(data)
    return path


def _utm(px, x0=500000.0, y0=4400000.0):
    return Affine(px, 0.0, x0, 0.0, -px, y0)


def _edges(n, rng=None, bands=1, dtype=np.uint16):
    """A scene of reflectance 0.2 / 0.6 halves (a vertical edge) with a horizontal edge below, as uint16."""
    y, x = np.mgrid[0:n, 0:n]
    r = np.where(x < n // 2 + 0.3 * (y - n / 2) / n * 10, 0.2, 0.6) + np.where(y > 2 * n // 3, 0.15, 0.0)
    a = np.round(r * 65535).astype(dtype)
    return np.stack([a] * bands)


def _touching(invalid: np.ndarray, k: float, shape_out) -> np.ndarray:
    """Independent rule: output pixel (i, j) is nodata when an invalid input pixel overlaps its pitch cell
    [i k, (i+1) k) x [j k, (j+1) k) with positive area."""
    out = np.zeros(shape_out, bool)
    rows, cols = np.nonzero(invalid)
    for n, m in zip(rows, cols, strict=True):
        for i in range(max(int(n / k) - 1, 0), min(int((n + 1) / k) + 2, shape_out[0])):
            if min(n + 1, (i + 1) * k) - max(n, i * k) <= 1e-9:
                continue
            for j in range(max(int(m / k) - 1, 0), min(int((m + 1) / k) + 2, shape_out[1])):
                if min(m + 1, (j + 1) * k) - max(m, j * k) > 1e-9:
                    out[i, j] = True
    return out


def test_a_multiband_utm_geotiff_comes_out_a_cog_in_its_crs_at_the_gsd(tmp_path):
    px = 0.245  # 2 input pixels per GSD: a 1100 px input gives 550 px, enough for an overview
    src = _write(tmp_path / "in.tif", _edges(1100, bands=3), transform=_utm(px), tiled=True, blockxsize=256,
                 blockysize=256)  # fmt: skip
    with rasterio.open(src, "r+") as d:
        d.descriptions = ("red", "green", "nir")
    out = tmp_path / "out.tif"
    r = runner.invoke(app, ["simulate", str(src), "--preset", "ankarasat3", "--seed", "3", "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert "x 3 bands" in r.output and "EPSG:32636" in r.output
    with rasterio.open(src) as i, rasterio.open(out) as o:
        assert o.count == 3 and o.crs == i.crs and o.descriptions == ("red", "green", "nir")
        assert o.transform.a == pytest.approx(SYSTEM.gsd_act_m, rel=1e-12)
        assert o.transform.e == pytest.approx(-SYSTEM.gsd_alt_m, rel=1e-12)
        assert (o.transform.c, o.transform.f) == (i.transform.c, i.transform.f)  # the footprint starts at the origin
        ib, ob = i.bounds, o.bounds
        assert ib.left == ob.left and ib.top == ob.top
        assert 0 <= ob.bottom - ib.bottom < GSD and 0 <= ib.right - ob.right < GSD  # whole pixels inside
        st = o.tags(ns="IMAGE_STRUCTURE")
        assert st["LAYOUT"] == "COG" and st["COMPRESSION"] == "DEFLATE"
        assert o.profile["tiled"] and o.block_shapes[0] == (512, 512) and o.overviews(1) == [2]
        assert o.dtypes[0] == "uint16" and o.nodata == 65535  # 12-bit DN: the top of uint16 is free for nodata
        a = o.read()
    assert a.shape == (3, 550, 550) and a.max() <= 4095
    assert not np.array_equal(a[0], a[1])  # each band has its own noise draw ...
    r2 = runner.invoke(app, ["simulate", str(src), "--preset", "ankarasat3", "--seed", "3", "--band", "2",
                             "-o", str(tmp_path / "b2.tif")])  # fmt: skip
    assert r2.exit_code == 0, r2.output
    with rasterio.open(tmp_path / "b2.tif") as b2:
        assert b2.count == 1 and b2.descriptions == ("green",)
        one = b2.read(1)
    assert np.abs(one.astype(int) - a[1]).max() <= 3 * math.sqrt(a[1].mean()) + 30  # same signal, own noise


@pytest.mark.parametrize(("px", "units"), [(0.1, "reflectance"), (0.07, "dn"), (0.098, "reflectance")])
def test_output_pixels_touching_input_nodata_are_nodata(tmp_path, px, units):
    rng = np.random.default_rng(int(px * 1000))
    a = _edges(280)[0]
    invalid = np.zeros(a.shape, bool)
    for _ in range(6):  # blobs and single pixels of nodata, anywhere
        y, x, h, w = rng.integers(0, 270), rng.integers(0, 270), rng.integers(1, 30), rng.integers(1, 30)
        invalid[y : y + h, x : x + w] = True
    invalid[rng.integers(0, 280, 20), rng.integers(0, 280, 20)] = True
    a[invalid] = 0
    src = _write(tmp_path / "in.tif", a, transform=_utm(px), nodata=0)
    out = tmp_path / "o.tif"
    r = simulate_file(src, out, SYSTEM, units=units, noise=False)
    k = GSD / px
    with rasterio.open(out) as o:
        img, nd = o.read(1), o.nodata
    expect = _touching(invalid, k, img.shape)
    got = np.isnan(img) if units == "reflectance" else img == nd
    assert r.shape_px == img.shape and expect.any()
    np.testing.assert_array_equal(got, expect)


def test_alpha_nan_and_an_internal_mask_are_nodata_too(tmp_path):
    a = _edges(210, bands=3).astype(np.uint16)
    alpha = np.full(a.shape[1:], 255, np.uint8)
    alpha[50:80, 100:150] = 0
    rgba = np.concatenate([a.astype(np.uint8) * 0 + (a >> 8).astype(np.uint8), alpha[None]])
    src = _write(tmp_path / "rgba.tif", rgba, transform=_utm(0.098), photometric="RGB", alpha="YES")
    r = simulate_file(src, tmp_path / "o.tif", SYSTEM, units="reflectance", noise=False)
    with rasterio.open(tmp_path / "o.tif") as o:
        img = o.read()
    assert r.count == 3 and img.shape[0] == 3  # the alpha band is the mask, not a band
    np.testing.assert_array_equal(np.isnan(img[0]), _touching(alpha == 0, GSD / 0.098, img.shape[1:]))
    f = _edges(210)[0].astype(np.float32) / 65535
    f[10:12, 10:40] = np.nan
    src = _write(tmp_path / "f.tif", f, transform=_utm(0.098))
    out = satchain.simulate_image(src, SYSTEM)
    np.testing.assert_array_equal(~out.valid, _touching(np.isnan(f), GSD / 0.098, out.image.shape))


def test_per_band_wavelengths_blur_the_longer_band_more(tmp_path):
    d = SYSTEM.to_dict()
    lam = SYSTEM.optics.wavelengths_m[0]
    d["bands"] = [{"name": "blue", "wavelengths_m": [4.5e-7]}, {"name": "own", "wavelengths_m": [lam]},
                  {"name": "nir", "wavelengths_m": [9.0e-7]}]  # fmt: skip
    system = satchain.ImagingSystem.from_dict(d)
    img = satchain.simulate_image(_edges(350, bands=3), system, pixel_m=0.07)
    plain = satchain.simulate_image(_edges(350)[0], SYSTEM, pixel_m=0.07)
    np.testing.assert_array_equal(img.image[1], plain.image)  # the band at the system's wavelength is the system
    slope = [np.abs(np.diff(b[5:20, :], axis=1)).max() for b in img.image]  # the vertical edge's sharpest step
    assert slope[0] > slope[1] > slope[2]  # diffraction: longer wavelength, wider PSF, softer edge
    with pytest.raises(ConfigError, match="2 bands but the system describes 3"):
        satchain.simulate_image(_edges(100, bands=2), system, pixel_m=0.07)


def test_geographic_crs_needs_a_pixel_size_and_keeps_its_crs_with_one(tmp_path):
    deg = Affine(1e-6, 0, 33.0, 0, -1e-6, 39.0)
    src = _write(tmp_path / "geo.tif", _edges(200)[0], transform=deg, crs="EPSG:4326")
    out = tmp_path / "o.tif"
    r = runner.invoke(app, ["simulate", str(src), "--preset", "ankarasat3", "-o", str(out)])
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "--scene-pixel-m" in r.stderr and "geographic" in r.stderr and not out.exists()
    r = runner.invoke(app, ["simulate", str(src), "--preset", "ankarasat3", "--scene-pixel-m", "0.098", "-o", str(out)])
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as o:
        assert o.crs.to_epsg() == 4326
        assert o.transform.a == pytest.approx(1e-6 * GSD / 0.098) and (o.transform.c, o.transform.f) == (33.0, 39.0)


def test_a_rotated_grid_keeps_its_rotation_and_a_jp2_or_nitf_input_works(tmp_path):
    t = _utm(0.098) @ Affine.rotation(20.0)
    src = _write(tmp_path / "rot.tif", _edges(150)[0], transform=t)
    r = simulate_file(src, tmp_path / "rot_o.tif", SYSTEM, units="reflectance", noise=False)
    assert r.transform.almost_equals(t @ Affine.scale(GSD / 0.098, SYSTEM.gsd_alt_m / 0.098))
    with rasterio.open(tmp_path / "rot_o.tif") as o:
        assert o.transform.almost_equals(r.transform)
    # NITF keeps UTM pixel-centre corners in whole metres (IGEOLO): a 2 m grid survives exactly (an output finer
    # than its input is allowed: the chain samples the band-limited image)
    for driver, name, px, n, kw in (
        ("JP2OpenJPEG", "in.jp2", 0.1, 200, {}),
        ("NITF", "in.ntf", 2.0, 40, {"ICORDS": "N"}),
    ):
        src = _write(tmp_path / name, _edges(n)[0], transform=_utm(px), driver=driver, **kw)
        out = tmp_path / f"{name}.tif"
        r = runner.invoke(app, ["simulate", str(src), "--preset", "ankarasat3", "--no-noise", "-o", str(out)])
        assert r.exit_code == 0, (driver, r.output)
        with rasterio.open(out) as o:
            assert o.crs.to_epsg() == 32636 and o.transform.a == pytest.approx(GSD, rel=1e-9)
            assert (o.transform.c, o.transform.f) == pytest.approx((500000.0, 4400000.0), abs=1e-6)
            assert o.tags(ns="IMAGE_STRUCTURE")["LAYOUT"] == "COG" and o.width == int(n * px / GSD + 1e-9)


def test_bad_rasters_are_one_line_errors_and_write_nothing(tmp_path):
    zero = _write(tmp_path / "allnd.tif", np.zeros((64, 64), np.uint16), transform=_utm(0.1), nodata=0)
    non_square = _write(tmp_path / "ns.tif", _edges(64)[0], transform=Affine(0.1, 0, 5e5, 0, -0.12, 4e6))
    cases = {
        zero: "every pixel is nodata",
        non_square: "not square",
    }
    for src, message in cases.items():
        out = tmp_path / "o.tif"
        r = runner.invoke(app, ["simulate", str(src), "--preset", "ankarasat3", "-o", str(out)])
        assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1, r.output
        assert message in r.stderr and str(src.name) in r.stderr
        assert not out.exists() and not out.with_suffix(".png").exists()
        assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    r = runner.invoke(app, ["simulate", str(non_square), "--preset", "ankarasat3", "--band", "4", "-o", str(out)])
    assert r.exit_code == 2 and "--band 4: must be an integer in [1, 1]" in r.stderr


def test_the_streamed_path_and_simulate_image_give_the_file_image(tmp_path, monkeypatch):
    a = _edges(400, bands=2)
    a[:, 30:60, 200:260] = 0
    src = _write(tmp_path / "in.tif", a, transform=_utm(0.098), nodata=0)
    full = simulate_file(src, tmp_path / "full.tif", SYSTEM, seed=7)
    mem = satchain.simulate_image(src, SYSTEM, units="dn", noise=True, seed=7)
    with rasterio.open(full.path) as o:
        f, nd = o.read(), o.nodata
    np.testing.assert_array_equal(np.where(mem.valid, mem.image, nd), f)  # bit for bit, noise included
    assert mem.transform == full.transform and mem.crs == full.crs
    monkeypatch.setattr(georaster, "_in_memory", lambda *a, **k: False)
    s = simulate_file(src, tmp_path / "s.tif", SYSTEM, seed=7, units="reflectance", noise=False)
    ref = satchain.simulate_image(src, SYSTEM, units="reflectance")
    with rasterio.open(s.path) as o:
        streamed = o.read()
    assert s.streamed and s.count == 2
    np.testing.assert_array_equal(np.isnan(streamed), ~ref.valid)
    assert np.nanmax(np.abs(streamed - ref.image)) < 1e-5


def test_simulate_image_of_an_array_has_the_engine_geometry():
    a = np.full((3, 100, 140), 0.25)
    a[1] = 0.5
    t = _utm(0.098)
    r = satchain.simulate_image(a, SYSTEM, transform=t, crs="EPSG:32636")
    assert r.image.shape == (3, 20, 28) and r.valid is None and r.crs == "EPSG:32636"
    np.testing.assert_allclose(r.image[1], 0.5, atol=1e-9)  # a flat field stays flat: the OTF is 1 at f = 0
    assert r.transform.almost_equals(t @ Affine.scale(5.0, 5.0)) and r.pixel_m == (GSD, SYSTEM.gsd_alt_m)
    with pytest.raises(ConfigError, match="pixel_m = None"):
        satchain.simulate_image(a[0], SYSTEM)


def test_a_sweep_over_rasters_writes_georeferenced_cases_and_checks_every_input_first(tmp_path):
    jp2 = _write(tmp_path / "a.jp2", _edges(120, bands=2), transform=_utm(0.098), driver="JP2OpenJPEG")
    tif = _write(tmp_path / "b.tif", _edges(120)[0], transform=_utm(0.098, 600000.0))
    out = tmp_path / "cases"
    r = runner.invoke(app, ["simulate", str(jp2), str(tif), "--preset", "ankarasat3", "--no-noise",
                            "--sweep", "motion.smear_px=1,2", "-o", str(out)])  # fmt: skip
    assert r.exit_code == 0, r.output
    images = sorted(out.glob("*.tif"))
    assert len(images) == 4
    for p in images:
        with rasterio.open(p) as o:
            assert o.crs.to_epsg() == 32636 and o.tags(ns="IMAGE_STRUCTURE")["LAYOUT"] == "COG"
            assert o.count == (2 if p.name.startswith("a") else 1)
            assert o.transform.c == (500000.0 if p.name.startswith("a") else 600000.0)
    geo = _write(tmp_path / "g.tif", _edges(120)[0], transform=Affine(1e-6, 0, 33, 0, -1e-6, 39), crs="EPSG:4326")
    out2 = tmp_path / "cases2"
    r = runner.invoke(app, ["simulate", str(tif), str(geo), "--preset", "ankarasat3", "--sweep",
                            "motion.smear_px=1,2", "-o", str(out2)])  # fmt: skip
    assert r.exit_code == 2 and "--scene-pixel-m" in r.stderr and "g.tif" in r.stderr
    assert not list(out2.glob("*.tif"))  # nothing simulated before every input was checked
