"""`measure ... --band N` reads one band of a multiband raster; the file's own mask (here an alpha band) is the
measurement's valid mask; a bad band is one line, exit 2 (issue 19)."""

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


def _edge(n=80, angle_deg=6.0, blur=0.8, lo=300.0, hi=3000.0) -> np.ndarray:
    """An exact blurred edge (Gaussian, pixel-integrated by 8 x 8 sub-samples) near x = n / 2."""
    t = np.deg2rad(angle_deg)
    o = (np.arange(8) + 0.5) / 8 - 0.5
    y, x = np.mgrid[0:n, 0:n].astype(float)
    acc = np.zeros((n, n))
    for dx in o:
        for dy in o:
            acc += ndtr(((x + dx - n / 2) * np.cos(t) - (y + dy - n / 2) * np.sin(t)) / blur)
    return lo + (hi - lo) * acc / 64


def _write(path, bands, *, alpha=None):
    count = len(bands) + (alpha is not None)
    prof = dict(driver="GTiff", height=bands[0].shape[0], width=bands[0].shape[1], count=count, dtype="uint16",
                crs="EPSG:32636", transform=Affine(0.5, 0.0, 500000.0, 0.0, -0.5, 4100000.0))  # fmt: skip
    with rasterio.open(path, "w", **prof) as d:
        for i, b in enumerate(bands, 1):
            d.write(np.round(b).astype("uint16"), i)
        if alpha is not None:
            d.write(alpha.astype("uint16"), count)
            d.colorinterp = [rasterio.enums.ColorInterp.gray] * len(bands) + [rasterio.enums.ColorInterp.alpha]


def test_band_picks_the_band_and_the_pixel_size_comes_from_the_file(tmp_path):
    edge = _edge()
    flat = np.full_like(edge, 1000.0)
    path = tmp_path / "three.tif"
    _write(path, [flat, edge, flat])
    r = runner.invoke(measure_app, ["edge", str(path), "--band", "2", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert abs(d["angle_deg"] - 6.0) < 0.1 and d["pixel_m"] == pytest.approx(0.5)
    flat_band = runner.invoke(measure_app, ["edge", str(path), "--band", "1", "--json"])
    assert flat_band.exit_code == 2  # a flat band has no edge: refused, not measured
    for bad in ("4", "0"):
        e = runner.invoke(measure_app, ["edge", str(path), "--band", bad])
        assert e.exit_code == 2 and "band" in e.stderr.lower() and len(e.stderr.strip().splitlines()) == 1


def test_alpha_band_is_the_mask_not_a_band(tmp_path):
    """Half the region hidden by alpha 0 and filled with 65535 there: without the mask it would read as clipped;
    with it the edge is measured from the visible half."""
    edge = _edge()
    alpha = np.full(edge.shape, 255)
    alpha[:, 60:] = 0
    hidden = edge.copy()
    hidden[:, 60:] = 65535
    path = tmp_path / "alpha.tif"
    _write(path, [hidden], alpha=alpha)
    r = runner.invoke(measure_app, ["edge", str(path), "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert abs(d["angle_deg"] - 6.0) < 0.15 and "clipping" not in d["flags"]
