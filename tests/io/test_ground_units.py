"""Ground units on every measurement of a raster with a metric transform (issue 19): ``pixel_m``, cy/m on the
ground, the CEOS table at ground frequencies; a pixel size that is not square or not known is said, not guessed;
a mask that leaves no usable edge is one line naming the file, exit 2.

The rasters are written here with rasterio: UTM (EPSG:32636) GeoTIFFs of 0.5 m pixels (Nyquist 1.0 cy/m), with
images rendered exactly by the test (edges integrated over the pixel, a sinusoidal star, a square-wave grating).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.special import ndtr
from typer.testing import CliRunner

from satchain.cli.measure import measure_app

rasterio = pytest.importorskip("rasterio")
from rasterio.transform import Affine  # noqa: E402

runner = CliRunner()
PIXEL_M = 0.5


def _edge(n=100, angle_deg=6.0, blur=0.7, lo=300.0, hi=3000.0) -> np.ndarray:
    """An exact Gaussian-blurred edge through the image centre, integrated over each pixel (8 x 8 samples)."""
    t = np.deg2rad(angle_deg)
    o = (np.arange(8) + 0.5) / 8 - 0.5
    y, x = np.mgrid[0:n, 0:n].astype(float)
    acc = sum(ndtr(((x + dx - n / 2) * np.cos(t) - (y + dy - n / 2) * np.sin(t)) / blur) for dx in o for dy in o)
    return lo + (hi - lo) * acc / 64


def _star(n=161, cycles=32) -> np.ndarray:
    y, x = np.mgrid[0:n, 0:n].astype(float) - (n - 1) / 2
    return 1000.0 + 400.0 * np.cos(cycles * np.arctan2(y, x))


def _write(path, img, *, pixel=(PIXEL_M, PIXEL_M), crs="EPSG:32636", nodata=None):
    prof = dict(driver="GTiff", height=img.shape[0], width=img.shape[1], count=1, dtype="uint16", nodata=nodata)
    if crs is not None:
        prof.update(crs=crs, transform=Affine(pixel[0], 0.0, 500000.0, 0.0, -pixel[1], 4100000.0))
    with rasterio.open(path, "w", **prof) as d:
        d.write(np.round(img).astype("uint16"), 1)
    return path


def _json(args) -> dict:
    r = runner.invoke(measure_app, [*args, "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def _table(args) -> str:
    r = runner.invoke(measure_app, args)
    assert r.exit_code == 0, r.output
    return r.stdout


def test_edge_carries_ground_units(tmp_path):
    path = _write(tmp_path / "edge.tif", _edge())
    d = _json(["edge", str(path)])
    assert d["pixel_m"] == PIXEL_M and d["nyquist_cy_per_m_ground"] == pytest.approx(1.0)
    f, g = np.array(d["f_cy_per_px"]), np.array(d["f_cy_per_m_ground"])
    np.testing.assert_allclose(g, f / PIXEL_M)
    assert g[np.argmin(np.abs(f - 0.5))] == pytest.approx(1.0)
    out = _table(["edge", str(path)])
    assert "MTF50 (cy/m ground)" in out and "f cy/m ground" in out and "Nyquist 1 cy/m" in out


def test_find_ceos_table_at_ground_frequencies(tmp_path):
    path = _write(tmp_path / "edge.tif", _edge())
    d = _json(["find", str(path)])
    assert d["pixel_m"] == PIXEL_M and d["nyquist_cy_per_m_ground"] == pytest.approx(1.0)
    tab = d["ceos_table"]
    fn, fg = np.array(tab["f_over_fs"]), np.array(tab["f_cy_per_m_ground"])
    np.testing.assert_allclose(np.diff(fn[fn != 0.25]), 0.02)  # steps of 0.02 ...
    assert fg[np.argmin(np.abs(fn - 0.25))] == pytest.approx(0.5)  # ... with the 0.25 row: 0.5 cy/m
    assert fg[np.argmin(np.abs(fn - 0.5))] == pytest.approx(1.0)  # Nyquist: 1.0 cy/m
    header, *rows = d["ceos_csv"].splitlines()
    assert header.split(",")[:2] == ["f_over_fs", "f_cy_per_m_ground"]
    assert "0.25,0.5," in d["ceos_csv"]
    act = d["combined"]["ACT"]
    np.testing.assert_allclose(act["f_cy_per_m_ground"], np.array(act["f_cy_per_px"]) / PIXEL_M)
    assert act["mtf50_cy_per_m_ground"] == pytest.approx(act["mtf50_cy_per_px"] / PIXEL_M)
    assert d["edges"][0]["mtf50_cy_per_m_ground"] == pytest.approx(d["edges"][0]["mtf50_cy_per_px"] / PIXEL_M)
    out = _table(["find", str(path)])
    assert "f cy/m" in out and "MTF50 cy/m" in out and "Nyquist 1 cy/m" in out


def test_star_and_bars_carry_ground_units(tmp_path):
    star = _write(tmp_path / "star.tif", _star())
    d = _json(["star", str(star), "--cycles", "32"])
    assert d["pixel_m"] == PIXEL_M and d["nyquist_cy_per_m_ground"] == pytest.approx(1.0)
    np.testing.assert_allclose(d["f_cy_per_m_ground"], np.array(d["f_cy_per_px"]) / PIXEL_M)
    assert "f cy/m ground" in _table(["star", str(star), "--cycles", "32"])
    x = np.arange(96)
    grating = np.where((x // 4) % 2 == 0, 800.0, 2400.0)[None, :] + np.zeros((40, 1))  # period 8 px, bars along y
    bars = _write(tmp_path / "bars.tif", grating)
    args = ["bars", str(bars), "--periods-px", "8", "--bars-per-group", "0", "--roi", "2,0,94,40"]
    args += ["--levels", "800,2400"]
    d = _json(args)
    assert d["pixel_m"] == PIXEL_M
    assert d["f_cy_per_m_ground"] == pytest.approx([0.125 / PIXEL_M])  # 1/8 cy/px = 0.25 cy/m
    assert "f cy/m ground" in _table(args)


@pytest.mark.filterwarnings("ignore:Dataset has no geotransform")
@pytest.mark.parametrize(
    ("kw", "why"),
    [({"pixel": (0.5, 0.6)}, "not square"), ({"crs": None}, "no ground pixel size")],
)
def test_unknown_or_non_square_pixel_is_said_not_guessed(tmp_path, kw, why):
    path = _write(tmp_path / "edge.tif", _edge(), **kw)
    d = _json(["edge", str(path)])
    assert d["pixel_m"] is None and d["f_cy_per_m_ground"] is None
    assert why in d["pixel_m_note"] and str(path) in d["pixel_m_note"]
    assert why in " ".join(_table(["edge", str(path)]).split())
    given = _json(["edge", str(path), "--pixel-m", "0.5"])  # --pixel-m decides
    assert given["pixel_m"] == 0.5 and "pixel_m_note" not in given


def _one_line_error(args, path) -> str:
    r = runner.invoke(measure_app, args)
    err = r.stderr.strip()
    assert r.exit_code == 2 and "Traceback" not in r.output and len(err.splitlines()) == 1, r.output
    assert err.startswith("error: ") and str(path) in err
    return err


@pytest.mark.parametrize("command", ["edge", "find"])
def test_mask_that_leaves_no_usable_edge_is_one_line(tmp_path, command):
    img = _edge()
    img[:, 30:70] = 0  # the file's nodata hides the edge: only the two flat plateaus are left
    path = _write(tmp_path / "masked.tif", img, nodata=0)
    err = _one_line_error([command, str(path)], path)
    assert "excludes 40 % of the pixels" in err
    err = _one_line_error([command, str(path), "--nodata", "300"], path)  # the dark plateau as well
    assert "excludes" in err
    full = _write(tmp_path / "all.tif", np.full((64, 64), 7.0))
    err = _one_line_error([command, str(full), "--nodata", "7"], full)
    assert "every pixel is excluded" in err
