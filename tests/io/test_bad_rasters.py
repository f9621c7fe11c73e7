"""Bad rasters, written here (rasterio or raw bytes), given to `satchain simulate` and `satchain measure edge|find`
(issue 19, point 5): each is one line on stderr that names the file, the problem and what fixes it, exit status 2,
no traceback, and nothing under the output name (no image, no preview, no hidden staging file). An RGBA raster
simulates (3 bands out, alpha as the mask) and measures band 1 by default or --band; a sweep checks every input
before its first case."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from _forged import forge_size
from scipy.special import ndtr
from typer.testing import CliRunner

from satchain.cli.main import app

rasterio = pytest.importorskip("rasterio")
from rasterio.transform import Affine  # noqa: E402

runner = CliRunner()
N = 96  # px a side: an edge of 96 px, 19 output px at 5 input px per GSD
PX = 0.098  # m: ankarasat3's 0.49 m GSD is 5 input pixels
UTM = Affine(PX, 0.0, 500000.0, 0.0, -PX, 4400000.0)
ANGLE = 5.0  # deg from the column axis


def _edge(lo: float = 0.2, hi: float = 0.6, blur: float = 0.8) -> np.ndarray:
    """Reflectance of a near-vertical edge through the centre, ANGLE deg off the columns, blurred by a Gaussian
    (sigma ``blur`` px) and integrated over each pixel by 8 x 8 sub-samples: the test's own exact renderer."""
    t = np.deg2rad(ANGLE)
    o = (np.arange(8) + 0.5) / 8 - 0.5
    y, x = np.mgrid[0:N, 0:N].astype(float)
    acc = sum(ndtr(((x + dx - N / 2) * np.cos(t) - (y + dy - N / 2) * np.sin(t)) / blur) for dx in o for dy in o)
    return lo + (hi - lo) * acc / 64


def _u16(r: np.ndarray) -> np.ndarray:
    return np.round(r * 65535).astype(np.uint16)


def _write(path: Path, data, *, transform=UTM, crs="EPSG:32636", nodata=None, driver="GTiff", **kw) -> Path:
    data = np.asarray(data)
    data = data[None] if data.ndim == 2 else data
    with rasterio.open(path, "w", driver=driver, width=data.shape[2], height=data.shape[1], count=data.shape[0],
                       dtype=data.dtype.name, crs=crs, transform=transform, nodata=nodata, **kw) as d:  # fmt: skip
        d.write(data)
    return path


def _huge_vrt(path: Path, small: Path, side: int) -> Path:
    """A VRT that claims ``side`` x ``side`` px in UTM, of which only ``small``'s N x N are backed by data."""
    path.write_text(
        f'<VRTDataset rasterXSize="{side}" rasterYSize="{side}"><SRS>EPSG:32636</SRS>'
        f"<GeoTransform>500000, {PX}, 0, 4400000, 0, -{PX}</GeoTransform>"
        '<VRTRasterBand dataType="UInt16" band="1"><SimpleSource>'
        f'<SourceFilename relativeToVRT="1">{small.name}</SourceFilename><SourceBand>1</SourceBand>'
        f'<SrcRect xOff="0" yOff="0" xSize="{N}" ySize="{N}"/><DstRect xOff="0" yOff="0" xSize="{N}" ySize="{N}"/>'
        "</SimpleSource></VRTRasterBand></VRTDataset>"
    )
    return path


@pytest.fixture(scope="module")
def bad(tmp_path_factory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("bad")
    edge = _edge()
    files = {"good": _write(d / "good.tif", _u16(edge))}
    with rasterio.Env() as env:
        if "JP2OpenJPEG" in env.drivers():
            jp2 = _write(d / "cut.jp2", _u16(edge), driver="JP2OpenJPEG", reversible="YES", quality="100")
            jp2.write_bytes(jp2.read_bytes()[: jp2.stat().st_size // 2])
            files["truncated_jp2"] = jp2
    forged = _write(d / "forged.tif", _u16(edge)[:64, :64], tiled=True, blockxsize=16, blockysize=16)
    forge_size(forged, 100_000)  # 10^10 px claimed in a few kB
    files["forged_header"] = forged
    files["huge_vrt"] = _huge_vrt(d / "huge.vrt", files["good"], 1_000_000)
    files["geographic"] = _write(
        d / "geo.tif", _u16(edge), crs="EPSG:4326", transform=Affine(1e-6, 0, 30, 0, -1e-6, 40)
    )
    files["complex"] = _write(d / "complex.tif", edge.astype(np.complex64))
    (d / "nobands.vrt").write_text(f'<VRTDataset rasterXSize="{N}" rasterYSize="{N}"></VRTDataset>')
    files["zero_bands"] = d / "nobands.vrt"
    files["all_nodata"] = _write(d / "allnd.tif", np.full((N, N), 7, np.uint16), nodata=7)
    masked = _u16(edge)
    masked[:, N // 2 - 14 : N // 2 + 14] = 0  # the area of interest leaves out the edge itself
    files["mask_hides_edge"] = _write(d / "aoi.tif", masked, nodata=0)
    files["non_square"] = _write(d / "nonsq.tif", _u16(edge), transform=Affine(PX, 0, 5e5, 0, -1.2 * PX, 4.4e6))
    files["sheared"] = _write(d / "shear.tif", _u16(edge), transform=Affine(PX, 0.2 * PX, 5e5, 0, -PX, 4.4e6))
    files["not_reflectance"] = _write(d / "x10000.tif", (edge * 10000).astype(np.float32))  # no scale in the file
    return files


# what the one line must say, besides the file's name; None: the command works on this raster
SIMULATE = {
    "truncated_jp2": ["cannot read"],
    "forged_header": ["claims 100000 x 100000 px", "forged header"],
    "huge_vrt": ["1000000 x 1000000 px", "crop or resample it first"],
    "geographic": ["geographic", "give --scene-pixel-m"],
    "complex": ["complex"],
    "zero_bands": ["bands"],
    "all_nodata": ["every pixel is nodata"],
    "mask_hides_edge": None,
    "non_square": ["not square", "resample it first"],
    "sheared": ["sheared", "resample it first"],
    "not_reflectance": ["2000..6000", "not reflectance", "give --input-scale"],
}
MEASURE = {
    "truncated_jp2": ["cannot read"],
    "forged_header": ["forged header"],
    "huge_vrt": ["1000000 x 1000000 px", "of memory"],
    "geographic": ["geographic", "give --pixel-m"],
    "complex": ["complex"],
    "zero_bands": ["bands"],
    "all_nodata": ["every pixel is nodata"],
    "mask_hides_edge": ["the mask / nodata excludes 29 % of the pixels"],
    "non_square": None,  # measured in cy/px, with a note (see below)
    "sheared": ["sheared", "give --pixel-m"],
    "not_reflectance": None,  # a measurement takes any values
}


def _refused(r, path: Path, phrases: list[str], out_dir: Path | None = None) -> str:
    """Exit 2, one line on stderr naming ``path`` and every phrase, no traceback; ``out_dir`` left empty."""
    assert r.exit_code == 2, (r.exit_code, r.output)
    assert isinstance(r.exception, SystemExit) and "Traceback" not in r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    assert path.name in lines[0] and all(p in lines[0] for p in phrases), lines[0]
    if out_dir is not None:
        assert sorted(p.name for p in out_dir.iterdir()) == []  # no OUT.tif, OUT.png, .OUT.tif.* staging
    return lines[0]


@pytest.mark.parametrize("case", sorted(SIMULATE))
def test_simulate_refuses_a_bad_raster_in_one_line_and_writes_nothing(bad, case, tmp_path):
    if case not in bad:
        pytest.skip("GDAL driver JP2OpenJPEG is not in this rasterio build")
    out = tmp_path / "out" / "OUT.tif"
    out.parent.mkdir()
    r = runner.invoke(app, ["simulate", str(bad[case]), "--preset", "ankarasat3", "-o", str(out)])
    if SIMULATE[case] is None:
        assert r.exit_code == 0, r.output
        return
    line = _refused(r, bad[case], SIMULATE[case], out.parent)
    if case == "huge_vrt":  # refused up front, on the disk it would fill or the memory it would need
        assert "GiB on disk" in line or "GiB of memory" in line


@pytest.mark.parametrize("command", ["edge", "find"])
@pytest.mark.parametrize("case", sorted(MEASURE))
def test_measure_refuses_a_bad_raster_in_one_line(bad, case, command):
    if case not in bad:
        pytest.skip("GDAL driver JP2OpenJPEG is not in this rasterio build")
    r = runner.invoke(app, ["measure", command, str(bad[case]), "--json"])
    if MEASURE[case] is None:
        assert r.exit_code == 0, r.output
        return
    _refused(r, bad[case], MEASURE[case])


def test_what_measure_takes_it_measures_right(bad):
    """Non-square pixels: measured in cy/px, no ground frequency, a note saying why; values that are not
    reflectance: measured as they are. The edge's angle is the rendered one either way."""
    nonsq = json.loads(runner.invoke(app, ["measure", "edge", str(bad["non_square"]), "--json"]).stdout)
    assert nonsq["pixel_m"] is None and "not square" in nonsq["pixel_m_note"] and "--pixel-m" in nonsq["pixel_m_note"]
    scaled = json.loads(runner.invoke(app, ["measure", "edge", str(bad["not_reflectance"]), "--json"]).stdout)
    for d in (nonsq, scaled):
        assert abs(abs(d["angle_deg"]) - ANGLE) < 0.2


def test_a_pixel_size_does_not_mend_a_sheared_or_non_square_grid(bad, tmp_path):
    for case in ("sheared", "non_square"):
        out = tmp_path / "OUT.tif"
        args = ["simulate", str(bad[case]), "--preset", "ankarasat3", "--scene-pixel-m", "0.1", "-o", str(out)]
        r = runner.invoke(app, args)
        _refused(r, bad[case], ["--scene-pixel-m sets a pixel size, not the grid"], tmp_path)
        assert r.exit_code == 2 and not out.exists()


def test_values_that_are_not_reflectance_simulate_with_the_scale_they_need(bad, tmp_path):
    out = tmp_path / "OUT.tif"
    args = [
        "simulate",
        str(bad["not_reflectance"]),
        "--preset",
        "ankarasat3",
        "--input-scale",
        "0.0001",
        "-o",
        str(out),
    ]
    r = runner.invoke(app, [*args, "--units", "reflectance", "--no-noise"])
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as o:
        img = o.read(1)
    assert np.all(np.isfinite(img)) and 0.19 < img.min() < img.max() < 0.61  # the 0.2 / 0.6 plateaus, blurred


# ------------------------------------------------------------------------------------------------ RGBA
def test_rgba_simulates_three_bands_with_alpha_as_the_mask_and_measures_one_band(tmp_path):
    edge = _u16(_edge())
    alpha = np.full((N, N), 65535, np.uint16)
    alpha[:, 83:] = 0  # input columns 83.. hidden
    src = _write(tmp_path / "rgba.tif", np.stack([edge, edge, edge, alpha]), photometric="RGB", alpha="YES")
    out = tmp_path / "o" / "sim.tif"
    r = runner.invoke(app, ["simulate", str(src), "--preset", "ankarasat3", "--no-noise", "-o", str(out)])
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as o:
        assert o.count == 3 and o.crs.to_epsg() == 32636
        data, nodata = o.read(), o.nodata
    # output column j covers input columns [5 j, 5 j + 5): it touches an alpha-0 pixel from j = 16 on
    assert data.shape == (3, N // 5, N // 5)
    assert np.all(data[:, :, 16:] == nodata) and np.all(data[:, :, :16] != nodata)
    r1 = runner.invoke(app, ["measure", "edge", str(src), "--json"])  # band 1 by default (the issue), with a warning
    assert r1.exit_code == 0 and "has 3 bands; band 1 is measured" in r1.stderr, r1.output
    d = json.loads(runner.invoke(app, ["measure", "edge", str(src), "--band", "2", "--json"]).stdout)
    assert abs(abs(d["angle_deg"]) - ANGLE) < 0.2 and d["pixel_m"] == pytest.approx(PX)
    assert json.loads(r1.stdout)["mtf_at_nyquist"] == pytest.approx(d["mtf_at_nyquist"], abs=1e-12)  # same bands


# ------------------------------------------------------------------------------------------------ sweeps
@pytest.mark.parametrize("case", ["not_reflectance", "geographic", "huge_vrt", "truncated_jp2", "sheared"])
def test_a_sweep_with_a_bad_input_fails_before_any_case(bad, case, tmp_path):
    if case not in bad:
        pytest.skip("GDAL driver JP2OpenJPEG is not in this rasterio build")
    out = tmp_path / "sweep"
    args = ["simulate", str(bad["good"]), str(bad[case]), "--preset", "ankarasat3", "--sweep", "motion.smear_px=1,2"]
    r = runner.invoke(app, [*args, "-o", str(out)])
    _refused(r, bad[case], SIMULATE[case])
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == []  # no case ran, no manifest
