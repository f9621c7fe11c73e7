"""satchain.io.raster and satchain.io.images on rasters this test writes with rasterio: GTiff, COG, JP2, NITF, VRT;
UTM and geographic; multiband; nodata, alpha; window reads against the array written; bad files refused in one line."""

from __future__ import annotations

import pickle
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
from _forged import forge_size
from hypothesis import given, settings
from hypothesis import strategies as st

rasterio = pytest.importorskip("rasterio")
from rasterio import Affine  # noqa: E402

from satchain.errors import ConfigError, InputError, SatchainIOError, SatchainWarning  # noqa: E402
from satchain.io import images as io  # noqa: E402
from satchain.io.raster import open_raster  # noqa: E402

SRC = str(Path(__file__).resolve().parents[2] / "src")
UTM = "EPSG:32636"
PX = 0.098
ORIGIN = (500_123.0, 4_400_456.0)


def _drivers() -> set[str]:
    with rasterio.Env() as env:
        return set(env.drivers())


def _write(path, data, *, driver="GTiff", crs=UTM, transform=None, **kw) -> Path:
    data = np.asarray(data)
    data = data[None] if data.ndim == 2 else data
    if transform is None and crs is not None:
        transform = Affine(PX, 0, ORIGIN[0], 0, -PX, ORIGIN[1])
    profile = dict(driver=driver, width=data.shape[2], height=data.shape[1], count=data.shape[0], dtype=data.dtype)
    if crs is not None:
        profile["crs"] = crs
    if transform is not None:
        profile["transform"] = transform
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rasterio.errors.NotGeoreferencedWarning)
        with rasterio.open(path, "w", **profile, **kw) as d:
            d.write(data)
    return Path(path)


def _bands(rows=70, cols=90, count=3, seed=0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 4096, (count, rows, cols), dtype=np.uint16)


# ------------------------------------------------------------------------------------------ formats, georeference
LOSSLESS = {
    "GTiff": {"tiled": True, "blockxsize": 32, "blockysize": 32, "compress": "deflate"},
    "COG": {"blocksize": 64, "compress": "deflate"},
    "JP2OpenJPEG": {"reversible": "YES", "quality": "100"},
    "NITF": {"icords": "N"},
}


@pytest.mark.parametrize("driver", list(LOSSLESS))
def test_every_format_reads_back_its_bands_and_metric_pixel_size(tmp_path, driver):
    if driver not in _drivers():
        pytest.skip(f"GDAL driver {driver} is not in this rasterio build")
    a = _bands(count=3)
    suffix = {"JP2OpenJPEG": ".jp2", "NITF": ".ntf"}.get(driver, ".tif")
    # NITF keeps the UTM pixel-centre corners in whole metres (IGEOLO): a 2 m grid on whole metres survives exactly
    px = 2.0 if driver == "NITF" else PX
    path = _write(tmp_path / f"a{suffix}", a, driver=driver, transform=Affine(px, 0, ORIGIN[0], 0, -px, ORIGIN[1]),
                  **LOSSLESS[driver])  # fmt: skip
    with open_raster(path) as r:
        assert r.shape == (70, 90) and r.count == 3 and r.dtype == np.uint16
        assert r.crs is not None and r.crs.to_epsg() == 32636
        assert r.pixel_m == pytest.approx((px, px), rel=1e-9)
        assert (r.transform.c, r.transform.f) == pytest.approx(ORIGIN, abs=1e-6)
        for b in (1, 2, 3):
            np.testing.assert_array_equal(r.read(band=b), a[b - 1])
    img, meta = io.read_image(path, band=2)
    np.testing.assert_array_equal(img, a[1])
    assert meta["pixel_m"] == pytest.approx(px) and meta["crs"] == UTM and meta["band"] == 2 and meta["count"] == 3


@settings(max_examples=40, deadline=None)
@given(st.data())
def test_window_reads_equal_the_slice_of_the_array(tmp_path_factory, data):
    path = tmp_path_factory.getbasetemp() / "win.tif"
    a = _bands(rows=101, cols=157, count=2, seed=5)
    if not path.exists():
        _write(path, a, tiled=True, blockxsize=32, blockysize=16, compress="lzw")
    r0 = data.draw(st.integers(0, 100))
    c0 = data.draw(st.integers(0, 156))
    h = data.draw(st.integers(1, 101 - r0))
    w = data.draw(st.integers(1, 157 - c0))
    band = data.draw(st.sampled_from([1, 2]))
    with open_raster(path, band=band) as r:
        np.testing.assert_array_equal(r.read(r0, c0, h, w), a[band - 1, r0 : r0 + h, c0 : c0 + w])
    with io.open_image(path, band=band) as r:
        np.testing.assert_array_equal(r.read(r0, c0, h, w), a[band - 1, r0 : r0 + h, c0 : c0 + w])


def test_multiband_without_a_band_named_uses_band_1_and_says_so(tmp_path):
    a = _bands(count=3)
    path = _write(tmp_path / "m.tif", a)
    with pytest.warns(SatchainWarning, match=r"3 samples \(bands\) per pixel: band 1 is used"):
        img, _ = io.read_image(path)
    np.testing.assert_array_equal(img, a[0])
    with open_raster(path) as r:
        with pytest.raises(ConfigError, match=r"has 3 bands; name one with --band N \(1\.\.3\)"):
            r.require_band()
        with pytest.raises(ConfigError, match=r"band = 4: must be an integer in \[1, 3\]"):
            r.read(band=4)
    with pytest.raises(ConfigError, match=r"band = 0: must be an integer in \[1, 3\]"):
        open_raster(path, band=0)


def test_geographic_crs_has_no_metric_pixel_size(tmp_path):
    path = _write(tmp_path / "g.tif", _bands(count=1), crs="EPSG:4326", transform=Affine(1e-6, 0, 32, 0, -1e-6, 40))
    with open_raster(path) as r:
        assert r.pixel_m is None and "geographic" in r.pixel_m_problem
        with pytest.raises(ConfigError, match=r"g\.tif.*geographic.*give --scene-pixel-m$"):
            r.require_pixel_m()
    _, meta = io.read_image(path)
    assert "pixel_m" not in meta and "degrees" in meta["invalid_pixel_m"]
    from satchain.scene.image import ImageScene

    with pytest.raises(ConfigError, match=r"g\.tif.*--scene-pixel-m"):
        ImageScene(path)
    assert ImageScene(path, pixel_m=0.5).pixel_m == 0.5  # the option overrides


def test_no_georeference_has_no_pixel_size_and_satchain_local_scale_is_metric(tmp_path):
    path = _write(tmp_path / "n.tif", _bands(count=1), crs=None)
    with open_raster(path) as r:
        assert r.pixel_m is None and "no georeference" in r.pixel_m_problem and not r.georeferenced
    io.write_tiff(tmp_path / "own.tif", np.zeros((8, 8), np.float32), pixel_m=0.25, origin_m=(3.0, 4.0))
    with open_raster(tmp_path / "own.tif") as r:  # satchain's own writer: a local metric pixel scale
        assert r.pixel_m == (0.25, 0.25) and (r.transform.c, r.transform.f) == (3.0, -4.0)


def test_projected_crs_in_feet_is_converted_to_metres(tmp_path):
    path = _write(tmp_path / "ft.tif", _bands(count=1), crs="EPSG:2227", transform=Affine(1.0, 0, 6e6, 0, -1.0, 2e6))
    with open_raster(path) as r:  # California zone 3, US survey feet
        assert r.pixel_m == pytest.approx((1200 / 3937, 1200 / 3937), rel=1e-9)


def test_rotated_transform_gives_the_step_lengths_and_sheared_is_refused(tmp_path):
    th = np.radians(16.8)
    rot = Affine(PX * np.cos(th), -2 * PX * np.sin(th), ORIGIN[0], PX * np.sin(th), 2 * PX * np.cos(th), ORIGIN[1])
    with open_raster(_write(tmp_path / "rot.tif", _bands(count=1), transform=rot)) as r:
        assert r.pixel_m == pytest.approx((PX, 2 * PX), rel=1e-12) and r.rotation_deg == pytest.approx(16.8)
    shear = Affine(PX, 0.3 * PX, ORIGIN[0], 0, -PX, ORIGIN[1])
    with open_raster(_write(tmp_path / "sh.tif", _bands(count=1), transform=shear)) as r:
        assert r.pixel_m is None and "sheared" in r.pixel_m_problem
        with pytest.raises(ConfigError, match="sheared.*--pixel-m"):
            r.require_pixel_m("--pixel-m")


def test_scale_offset_and_band_names_and_bit_depth(tmp_path):
    a = _bands(count=2)
    path = tmp_path / "s.tif"
    _write(path, a, nbits=12)
    with rasterio.open(path, "r+") as d:
        d.scales, d.offsets = (2e-5, 1e-4), (-0.1, 0.0)
        d.descriptions = ("B04 red", "B08 nir")
    with open_raster(path) as r:
        assert r.descriptions == ("B04 red", "B08 nir") and r.bit_depth == 12
        np.testing.assert_allclose(r.read(3, 4, 5, 6, scaled=True), a[0, 3:8, 4:10] * 2e-5 - 0.1, rtol=1e-12)
        np.testing.assert_array_equal(r.read(3, 4, 5, 6, band=2), a[1, 3:8, 4:10])
    _, meta = io.read_image(path, band=1)
    assert meta["band_names"] == ["B04 red", "B08 nir"] and meta["bit_depth"] == 12
    assert io.integer_scale(np.uint16, meta) == 1 / 4095


def test_vrt_window_of_a_geotiff(tmp_path):
    a = _bands(count=1)
    _write(tmp_path / "src.tif", a)
    (tmp_path / "v.vrt").write_text(textwrap.dedent("""\
        <VRTDataset rasterXSize="40" rasterYSize="30">
          <VRTRasterBand dataType="UInt16" band="1"><SimpleSource>
            <SourceFilename relativeToVRT="1">src.tif</SourceFilename><SourceBand>1</SourceBand>
            <SrcRect xOff="10" yOff="20" xSize="40" ySize="30"/><DstRect xOff="0" yOff="0" xSize="40" ySize="30"/>
          </SimpleSource></VRTRasterBand>
        </VRTDataset>"""))  # fmt: skip
    img, meta = io.read_image(tmp_path / "v.vrt")
    np.testing.assert_array_equal(img, a[0, 20:50, 10:50])
    assert meta["format"] == "vrt" and "pixel_m" not in meta


def test_readers_pickle_by_path(tmp_path):
    a = _bands(count=2)
    path = _write(tmp_path / "p.tif", a)
    for reader in (open_raster(path, band=2), io.open_image(path, band=2)):
        clone = pickle.loads(pickle.dumps(reader))
        np.testing.assert_array_equal(clone.read(1, 2, 3, 4), a[1, 1:4, 2:6])
        clone.close()
        reader.close()


# ------------------------------------------------------------------------------------------ masks: nodata, alpha
def test_nodata_becomes_the_mask(tmp_path):
    a = _bands(count=1)[0]
    a[:, :20] = 0  # the area outside the target, as cal/val tools set it
    path = _write(tmp_path / "nd.tif", a, nodata=0)
    with open_raster(path) as r:
        assert r.has_mask and r.nodata == 0
        np.testing.assert_array_equal(r.read_mask(5, 10, 20, 30), a[5:25, 10:40] != 0)
    img, valid, meta = io.read_image(path, mask=True)
    np.testing.assert_array_equal(valid, a != 0)
    assert meta["nodata"] == 0 and meta["valid_fraction"] == pytest.approx(np.mean(a != 0))
    _, valid, _ = io.read_image(_write(tmp_path / "free.tif", a), mask=True)
    assert valid is None  # no nodata, mask or alpha: every pixel valid


def test_rgba_alpha_is_the_mask_not_a_band(tmp_path):
    rgb = _bands(count=3).astype(np.uint8)
    alpha = np.full(rgb.shape[1:], 255, np.uint8)
    alpha[10:30, 40:60] = 0
    path = _write(tmp_path / "rgba.tif", np.concatenate([rgb, alpha[None]]), photometric="RGB", alpha="YES")
    with open_raster(path) as r:
        assert r.count == 3 and r.alpha_band == 4 and r.has_mask
        np.testing.assert_array_equal(r.read_mask(), alpha > 0)
    luma = np.rint(rgb.astype(float).transpose(1, 2, 0) @ [0.299, 0.587, 0.114])
    with pytest.warns(SatchainWarning, match=r"RGB image \(3 samples per pixel\) converted to grey"):
        img, valid, _ = io.read_image(path, mask=True)
    assert np.max(np.abs(img - luma)) <= 0.5 and np.array_equal(valid, alpha > 0)
    with pytest.raises(ConfigError, match=r"band = 4: must be an integer in \[1, 3\]"):
        io.read_image(path, band=4)


# ------------------------------------------------------------------------------------------ bad files: one line
def _one_line(exc_info, name: str) -> str:
    msg = str(exc_info.value)
    assert "\n" not in msg and name in msg, msg
    return msg


def test_nodata_everywhere_is_refused(tmp_path):
    path = _write(tmp_path / "empty.tif", np.full((16, 16), 7, np.uint16), nodata=7)
    with pytest.raises(InputError, match="every pixel is nodata") as e:
        io.read_image(path)
    _one_line(e, "empty.tif")


def test_complex_and_bandless_rasters_are_refused(tmp_path):
    path = _write(tmp_path / "c.tif", np.ones((8, 8), np.complex64))
    with pytest.raises(InputError, match="complex") as e:
        open_raster(path)
    _one_line(e, "c.tif")
    (tmp_path / "none.vrt").write_text('<VRTDataset rasterXSize="8" rasterYSize="8"></VRTDataset>')
    with pytest.raises((InputError, SatchainIOError), match="bands") as e:  # GDAL itself refuses it
        io.read_image(tmp_path / "none.vrt")
    _one_line(e, "none.vrt")


def test_truncated_jp2_is_refused(tmp_path):
    if "JP2OpenJPEG" not in _drivers():
        pytest.skip("GDAL driver JP2OpenJPEG is not in this rasterio build")
    path = _write(tmp_path / "t.jp2", _bands(rows=256, cols=256, count=1), driver="JP2OpenJPEG", reversible="YES",
                  quality="100")  # fmt: skip
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(SatchainIOError, match="cannot read") as e:
        io.read_image(path)
    _one_line(e, "t.jp2")


def test_header_claiming_1e10_pixels_is_refused_before_reading(tmp_path):
    path = _write(tmp_path / "huge.tif", np.ones((64, 64), np.uint16), crs=None, tiled=True, blockxsize=16,
                  blockysize=16)  # fmt: skip
    forge_size(path, 100_000)  # 10^10 pixels claimed in a file of a few kB
    with pytest.raises(SatchainIOError, match=r"claims 100000 x 100000 px .* damaged or forged header") as e:
        open_raster(path)
    _one_line(e, "huge.tif")
    p = subprocess.run([sys.executable, "-m", "satchain.cli.main", "measure", "edge", str(path), "--pixel-m", "1"],
                       capture_output=True, text=True, env={"PYTHONPATH": SRC, "PATH": ""})  # fmt: skip
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "damaged or forged" in p.stderr


# ------------------------------------------------------------------------------------------ memory: by window
def test_one_window_of_a_large_tiled_file_does_not_load_the_file(tmp_path):
    """8000 x 8000 uint16 (128 MB decoded): reading a 256 x 256 window raises the peak RSS by far less."""
    path = tmp_path / "big.tif"
    ramp = (np.arange(512, dtype=np.uint16)[:, None] * 7 + np.arange(8000, dtype=np.uint16)[None]).astype(np.uint16)
    with rasterio.open(path, "w", driver="GTiff", width=8000, height=8000, count=1, dtype="uint16", tiled=True,
                       blockxsize=256, blockysize=256, compress="deflate", crs=UTM,
                       transform=Affine(PX, 0, ORIGIN[0], 0, -PX, ORIGIN[1])) as d:  # fmt: skip
        for r0 in range(0, 8000, 512):
            h = min(512, 8000 - r0)
            d.write(ramp[:h], 1, window=((r0, r0 + h), (0, 8000)))
    code = textwrap.dedent(f"""
        import numpy as np
        from satchain.io.raster import open_raster
        def kb(key):
            return int(next(l for l in open("/proc/self/status") if l.startswith(key)).split()[1])
        r = open_raster({str(path)!r})
        r.read(0, 0, 16, 16)  # GDAL and its drivers loaded
        base = kb("VmRSS:")
        w = r.read(4000, 4000, 256, 256)
        assert w.shape == (256, 256)
        print(kb("VmHWM:") - base)
    """)
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env={"PYTHONPATH": SRC})
    assert p.returncode == 0, p.stderr
    grew_mb = int(p.stdout.split()[-1]) / 1024
    assert grew_mb < 16, f"peak RSS grew {grew_mb:.1f} MB reading one 256 x 256 window of a 128 MB image"
    with open_raster(path) as r:
        np.testing.assert_array_equal(r.read(4096, 4000, 256, 256), ramp[:256, 4000:4256])
