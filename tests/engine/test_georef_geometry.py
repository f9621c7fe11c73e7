"""Issue 29, items 13-14: `satchain simulate IN.tif --focal-plane FP.tif` under pushbroom geometry (yaw steering,
Earth rotation at latitude 40: shear and along-track scale) georeferences both outputs through the image's mean map,
so a GIS places every output pixel over the ground it images. Bright squares at known CRS coordinates are found in
OUT.tif and FP.tif by their centroids, which the files' transforms must map back onto those coordinates; without
any geometry the transforms stay the plain scaled input transform."""

from __future__ import annotations

import numpy as np
import pytest
import rasterio
from rasterio import Affine
from scipy import ndimage
from typer.testing import CliRunner

from satchain.cli.main import app

runner = CliRunner()
PX, N = 0.07, 600
T_IN = Affine(PX, 0.0, 500123.4, 0.0, -PX, 4400567.8)  # a nonzero origin, UTM 36N
BG, SPOT = 0.2, 0.9
HALF_PX = 10  # squares of 2 * HALF_PX input pixels (1.4 m, about 3 output pixels)
# square centres, input pixel coordinates (col, row) on pixel corners: away from the pivot, in every quadrant
CENTRES_PX = [(110.0, 120.0), (480.0, 150.0), (140.0, 470.0), (460.0, 450.0)]
GEOMETRY = {
    "static": "",
    "yaw": "latitude_deg = 40.0\ninclination_deg = 97.6\nearth_rotation = true\nyaw_steering = true\n",
    "earth40": "latitude_deg = 40.0\ninclination_deg = 97.6\nearth_rotation = true\n",
}


def _squares(path):
    a = np.full((N, N), BG, dtype=np.float32)
    for c, r in CENTRES_PX:
        a[int(r) - HALF_PX : int(r) + HALF_PX, int(c) - HALF_PX : int(c) + HALF_PX] = SPOT
    with rasterio.open(path, "w", driver="GTiff", width=N, height=N, count=1, dtype="float32", crs="EPSG:32636",
                       transform=T_IN) as d:  # fmt: skip
        d.write(a, 1)
    return path, [T_IN @ c for c in CENTRES_PX]


def _system_file(tmp_path, extra: str):
    from importlib import resources

    text = resources.files("satchain.presets").joinpath("ankarasat3.toml").read_text()
    anchor = "[orbit]\naltitude_m = 567000.0\n"
    assert anchor in text
    p = tmp_path / "sys.toml"
    p.write_text(text.replace(anchor, anchor + extra))
    return p


def _centroids(img: np.ndarray) -> list[tuple[float, float]]:
    """(col, row) centroids (pixel corners, as a transform reads them) of the bright blobs."""
    img = np.nan_to_num(img, nan=BG)
    w = np.clip(img - BG, 0, None)
    labels, n = ndimage.label(img > BG + 0.3 * (SPOT - BG))
    out = []
    for k in range(1, n + 1):
        near = ndimage.binary_dilation(labels == k, iterations=3)
        ww = np.where(near, w, 0.0)
        rows, cols = np.indices(img.shape)
        out.append(((ww * cols).sum() / ww.sum() + 0.5, (ww * rows).sum() / ww.sum() + 0.5))
    return out


def _check(path, known_xy, tol_px: float = 0.5):
    with rasterio.open(path) as f:
        assert f.crs.to_epsg() == 32636
        t, img = f.transform, f.read(1)
    found = [t @ c for c in _centroids(img)]
    assert len(found) == len(known_xy)
    pixel_m = np.sqrt(abs(t.determinant))
    for x, y in known_xy:
        miss = min(np.hypot(fx - x, fy - y) for fx, fy in found)
        assert miss < tol_px * pixel_m, f"{path.name}: spot at ({x:.2f}, {y:.2f}) placed {miss / pixel_m:.2f} px away"
    return t


@pytest.mark.parametrize("geometry", ["yaw", "earth40", "static"])
def test_outputs_place_each_spot_on_its_ground_coordinates(tmp_path, geometry):
    src, known = _squares(tmp_path / "in.tif")
    sysf = _system_file(tmp_path, GEOMETRY[geometry])
    out, fp = tmp_path / "out.tif", tmp_path / "fp.tif"
    r = runner.invoke(app, ["simulate", str(src), "--system", str(sysf), "--units", "reflectance", "--no-noise",
                            "-o", str(out), "--focal-plane", str(fp)])  # fmt: skip
    assert r.exit_code == 0, r.output
    t_out = _check(out, known)
    t_fp = _check(fp, known)
    if geometry == "static":  # the guard: no geometry, the plain transforms, exactly as before
        from satchain import load_system

        k = load_system(sysf).gsd_act_m / PX
        assert t_out == T_IN @ Affine.scale(k, k) and t_fp == T_IN
    else:
        assert t_out.b != 0 or t_out.d != 0  # the map is turned or sheared, not a plain scale
        from satchain.io.images import read_image

        _, meta = read_image(out)  # measurements still read the detector pixel's ground size, the GSD
        assert meta["pixel_m"] == pytest.approx(0.49) and "pixel_m_xy" not in meta and "invalid_pixel_m" not in meta


@pytest.mark.parametrize("geometry", ["yaw", "earth40"])
def test_simulate_image_with_a_transform_places_each_spot_as_the_file_path_does(tmp_path, geometry):
    """The Python API (an array with its transform) georeferences through the same image map as the CLI."""
    from satchain import load_system
    from satchain.engine.degrade import simulate_image

    src, known = _squares(tmp_path / "in.tif")
    with rasterio.open(src) as f:
        a = f.read(1)
    sim = simulate_image(a, load_system(_system_file(tmp_path, GEOMETRY[geometry])), transform=T_IN,
                         units="reflectance", noise=False)  # fmt: skip
    t = sim.transform
    found = [t @ c for c in _centroids(np.asarray(sim.image))]
    pixel_m = np.sqrt(abs(t.determinant))
    for x, y in known:
        assert min(np.hypot(fx - x, fy - y) for fx, fy in found) < 0.5 * pixel_m
