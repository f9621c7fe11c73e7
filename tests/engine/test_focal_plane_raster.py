"""Issue 29 follow-up: `satchain simulate --focal-plane` of a GeoTIFF honours its nodata exactly as the plain path
does and keeps its georeference: the focal plane is on the input's CRS, its transform the ground footprint of its
samples (the input's on the input grid, D x D input pixels on the coarse grid), NaN where it sits on invalid input."""

from __future__ import annotations

import numpy as np
import pytest
import rasterio
from rasterio import Affine
from typer.testing import CliRunner

from satchain.cli.main import app

runner = CliRunner()
T_IN = Affine(0.07, 0.0, 500000.0, 0.0, -0.07, 4400000.0)


def _zero_filled_edge(path, n=256, fill_cols=40, dtype="uint16", nodata=0):
    """A 5-degree edge of reflectance 0.1 / 0.8 (as uint16 DN) whose first ``fill_cols`` columns are nodata."""
    y, x = np.mgrid[0:n, 0:n]
    r = np.where((x - n / 2) * np.cos(0.087) + (y - n / 2) * np.sin(0.087) > 0, 0.8, 0.1)
    a = np.round(r * 65535).astype(dtype) if dtype == "uint16" else r.astype(dtype)
    a[:, :fill_cols] = nodata
    with rasterio.open(path, "w", driver="GTiff", width=n, height=n, count=1, dtype=dtype, crs="EPSG:32636",
                       transform=T_IN, nodata=nodata) as d:  # fmt: skip
        d.write(a, 1)
    return path, a != nodata


def _sim(src, out, *extra):
    r = runner.invoke(app, ["simulate", str(src), "--preset", "ankarasat3", "--no-noise", "--units", "reflectance",
                            "-o", str(out), *extra])  # fmt: skip
    assert r.exit_code == 0, r.output
    return r


def test_focal_plane_run_keeps_the_plain_image_its_nodata_and_the_georeference(tmp_path):
    src, valid = _zero_filled_edge(tmp_path / "in.tif")
    _sim(src, tmp_path / "a.tif")
    _sim(src, tmp_path / "b.tif", "--focal-plane", str(tmp_path / "fp.tif"))
    with rasterio.open(tmp_path / "a.tif") as a, rasterio.open(tmp_path / "b.tif") as b:
        assert b.crs == a.crs and b.transform == a.transform
        ia, ib = a.read(1), b.read(1)
    assert np.isnan(ib[:, 0]).all(), "output pixels over the input's nodata are nodata"
    np.testing.assert_array_equal(np.isnan(ia), np.isnan(ib))
    np.testing.assert_allclose(ib, ia, rtol=0, atol=1e-6, equal_nan=True)  # the fill is not blurred in
    with rasterio.open(tmp_path / "fp.tif") as f:
        assert f.crs.to_epsg() == 32636 and f.transform == T_IN and f.shape == valid.shape
        fp = f.read(1)
    np.testing.assert_array_equal(np.isnan(fp), ~valid)  # NaN exactly on the invalid input pixels
    # far from the edge and from the fill the focal plane is the ground reflectance
    assert fp[10:30, 60:90] == pytest.approx(0.1, abs=0.03) and fp[200:250, 220:250] == pytest.approx(0.8, abs=0.03)


def test_coarse_focal_plane_transform_is_its_samples_footprint_and_float_nodata_is_not_values(tmp_path):
    src, valid = _zero_filled_edge(tmp_path / "in.tif", dtype="float32", nodata=-9999.0)
    _sim(src, tmp_path / "b.tif", "--focal-plane", str(tmp_path / "fp.tif"), "--focal-plane-grid", "coarse")
    with rasterio.open(tmp_path / "fp.tif") as f:
        t, fp = f.transform, f.read(1)
        assert f.crs.to_epsg() == 32636
    d = round(t.a / T_IN.a)
    assert d >= 2 and t == T_IN @ Affine.scale(d, d)
    # sample (j, i) is the D x D block it is centred on: NaN exactly where that block touches the fill
    cols_bad = np.nonzero(np.isnan(fp[5]))[0]
    assert cols_bad.max() == -(-40 // d) - 1 and len(cols_bad) == -(-40 // d)
    assert fp[5:15, 60 // d : 90 // d] == pytest.approx(0.1, abs=0.03)
