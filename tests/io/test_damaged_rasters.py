"""Issue 29 item 18: a raster GDAL cannot read is refused in one line that says why -- truncated, corrupt, or
the VRT's source file missing -- with GDAL's own message kept in the exception chain."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import rasterio
from rasterio import Affine
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.errors import SatchainIOError
from satchain.io.raster import open_raster

runner = CliRunner()
N = 256


def _write(path: Path, driver: str = "GTiff", **kw) -> Path:
    a = (np.random.default_rng(1).random((N, N)) * 60000).astype(np.uint16)
    with rasterio.open(path, "w", driver=driver, width=N, height=N, count=1, dtype="uint16", crs="EPSG:32636",
                       transform=Affine(0.07, 0, 5e5, 0, -0.07, 4.4e6), **kw) as d:  # fmt: skip
        d.write(a, 1)
    return path


def _truncated(tmp_path: Path) -> Path:
    p = _write(tmp_path / "cut.tif")
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    return p


def _corrupt(tmp_path: Path) -> Path:
    """Garbage bytes in the middle of the (DEFLATE) strip data; the file keeps its size."""
    p = _write(tmp_path / "bad.tif", compress="deflate")
    data = bytearray(p.read_bytes())
    mid = len(data) // 2
    data[mid : mid + 4000] = np.random.default_rng(2).integers(0, 256, 4000, dtype=np.uint8).tobytes()
    p.write_bytes(bytes(data))
    return p


def _vrt_without_source(tmp_path: Path) -> Path:
    src = _write(tmp_path / "source.tif")
    vrt = tmp_path / "mosaic.vrt"
    vrt.write_text(
        f'<VRTDataset rasterXSize="{N}" rasterYSize="{N}"><SRS>EPSG:32636</SRS>'
        "<GeoTransform>500000, 0.07, 0, 4400000, 0, -0.07</GeoTransform>"
        '<VRTRasterBand dataType="UInt16" band="1"><SimpleSource>'
        '<SourceFilename relativeToVRT="1">source.tif</SourceFilename><SourceBand>1</SourceBand>'
        f'<SrcRect xOff="0" yOff="0" xSize="{N}" ySize="{N}"/><DstRect xOff="0" yOff="0" xSize="{N}" ySize="{N}"/>'
        "</SimpleSource></VRTRasterBand></VRTDataset>"
    )
    with open_raster(vrt) as r:  # the VRT reads while its source is there
        assert r.read(0, 0, 4, 4).shape == (4, 4)
    os.remove(src)
    return vrt


def _vrt_with_truncated_source(tmp_path: Path) -> Path:
    vrt = _vrt_without_source(tmp_path)
    src = _write(tmp_path / "source.tif")
    src.write_bytes(src.read_bytes()[: src.stat().st_size // 2])
    return vrt


def _truncated_jp2(tmp_path: Path) -> Path:
    with rasterio.Env() as env:
        if "JP2OpenJPEG" not in env.drivers():
            pytest.skip("GDAL has no JP2 driver here")
    p = _write(tmp_path / "cut.jp2", driver="JP2OpenJPEG", reversible="YES", quality="100")
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    return p


CASES = {
    "truncated": (_truncated, ["truncated", "cut short"]),
    "corrupt": (_corrupt, ["corrupt"]),
    "vrt_source_missing": (_vrt_without_source, ["source file", "source.tif", "missing"]),
    "vrt_source_truncated": (_vrt_with_truncated_source, ["source file", "source.tif", "truncated"]),
    "truncated_jp2": (_truncated_jp2, ["truncated"]),
}


@pytest.mark.parametrize("case", CASES)
def test_a_damaged_raster_says_why_and_keeps_gdals_message_in_the_chain(tmp_path, case):
    make, phrases = CASES[case]
    path = make(tmp_path)
    with pytest.raises(SatchainIOError) as info, open_raster(path) as r:
        r.read()
    text = str(info.value)
    assert path.name in text and all(p in text for p in phrases), text
    assert "See previous exception" not in text and "\n" not in text
    assert info.value.__cause__ is not None  # GDAL's own error, for --debug and bug reports
    assert "corrupt" not in text or case == "corrupt"


@pytest.mark.parametrize("case", ["truncated", "corrupt", "vrt_source_missing"])
def test_simulate_refuses_a_damaged_raster_in_one_line_and_writes_nothing(tmp_path, case):
    make, phrases = CASES[case]
    path = make(tmp_path)
    out = tmp_path / "out.tif"
    r = runner.invoke(app, ["simulate", str(path), "--preset", "ankarasat3", "-o", str(out)])
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert all(p in line for p in phrases) and "unexpected" not in line, line
    assert not out.exists()
