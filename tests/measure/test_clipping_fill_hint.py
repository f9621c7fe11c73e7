"""Issue 29 item 19: a zero fill along the pixel axes of a uint16 GeoTIFF without a nodata tag (kept as data, as
the README says: the step alone cannot tell it from a dark area clipped at 0) makes the edge look clipped; the
refusal says the zeros may be a fill and to give --nodata 0, with which the edge measures."""

from __future__ import annotations

import json

import numpy as np
import rasterio
from _render_audit import render_gauss_edge
from rasterio import Affine
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.measure._clipping import find_clipping

runner = CliRunner()


def _crop_with_fill(path):
    """A noisy 5 deg edge (DN 8000 -> 24000), the left 40 columns set to 0 (an area-of-interest fill), no nodata
    tag."""
    edge = render_gauss_edge((160, 160), 5.0, sigma_px=0.8, phase_px=20.0, low=8000.0, high=24000.0, sub=8)
    a = np.round(edge + np.random.default_rng(3).normal(0.0, 60.0, edge.shape)).astype(np.uint16)
    a[:, :40] = 0
    with rasterio.open(path, "w", driver="GTiff", width=160, height=160, count=1, dtype="uint16", crs="EPSG:32636",
                       transform=Affine(0.5, 0, 5e5, 0, -0.5, 4.4e6)) as d:  # fmt: skip
        d.write(a, 1)
    return path, a


def test_a_zero_plateau_at_the_minimum_names_the_fill_and_the_nodata_option(tmp_path):
    path, a = _crop_with_fill(tmp_path / "crop.tif")
    clip = find_clipping(a)
    assert clip is not None and clip.side == "minimum" and clip.level == 0
    assert "--nodata 0" in clip.message and "fill" in clip.message
    r = runner.invoke(app, ["measure", "edge", str(path)])
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert "--nodata 0" in line and "fill" in line
    r = runner.invoke(app, ["measure", "edge", str(path), "--nodata", "0", "--json"])
    assert r.exit_code == 0, r.output
    res = json.loads(r.stdout)
    assert abs(abs(res["angle_deg"]) - 5.0) < 0.5  # the edge itself, not the fill's border


def test_a_plateau_at_a_non_zero_minimum_gets_no_fill_advice():
    edge = render_gauss_edge((120, 120), 5.0, sigma_px=0.8, low=8000.0, high=24000.0, sub=8)
    a = np.round(edge + np.random.default_rng(4).normal(0.0, 60.0, edge.shape))
    a = np.maximum(a, 9000.0).astype(np.uint16)  # clipped at 9000 DN: a real clip
    clip = find_clipping(a)
    assert clip is not None and clip.side == "minimum" and "--nodata" not in clip.message
