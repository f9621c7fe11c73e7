"""`satchain simulate` of GDAL rasters (issue 29): a system without ``bit_depth`` writes reflectance, float options
that are not finite and > 0 are refused by name, a pixel size that contradicts the file's is refused, and an input
whose valid data cannot give one valid output pixel is refused instead of written as 100 % nodata."""

from __future__ import annotations

import json

import numpy as np
import pytest
import rasterio
from rasterio import Affine
from typer.testing import CliRunner

import satchain
from satchain.cli.main import app
from satchain.errors import ConfigError

runner = CliRunner()
PX = 0.07

#: a complete but minimal system file: no full_well_e, no bit_depth (as the README's mycamera.toml)
MINIMAL = """name = "mini"
[orbit]
altitude_m = 567000.0
[optics]
aperture_diameter_m = 0.70
f_number = 9.72
wavelengths_m = [6.5e-7]
[detector]
pitch_m = 5.88e-6
"""
PUSHBROOM = """[motion]
[[motion.oscillation]]
axis = "act"
amplitude_px = 0.5
frequency_hz = 4465.0
"""


def _write(path, data, *, px=PX, nodata=None):
    data = np.asarray(data)
    data = data[None] if data.ndim == 2 else data
    with rasterio.open(path, "w", driver="GTiff", width=data.shape[2], height=data.shape[1], count=data.shape[0],
                       dtype=data.dtype.name, crs="EPSG:32636", transform=Affine(px, 0, 5e5, 0, -px, 4.4e6),
                       nodata=nodata) as d:  # fmt: skip
        d.write(data)
    return path


def _edge(n=240, bands=1) -> np.ndarray:
    """Reflectance 0.2 | 0.6 across a vertical edge, as float32."""
    x = np.arange(n)[None, :] + np.zeros((n, 1))
    a = np.where(x < n / 2, 0.2, 0.6).astype(np.float32)
    return np.stack([a] * bands)


def _sim(*args):
    return runner.invoke(app, ["simulate", *map(str, args)])


@pytest.fixture()
def minimal(tmp_path):
    p = tmp_path / "mycamera.toml"
    p.write_text(MINIMAL)
    return p


# ------------------------------------------------------------------------------------- item 1: no bit_depth
@pytest.mark.parametrize("extra", ["", "--band 1", "pushbroom"])
def test_reflectance_without_noise_from_a_system_without_bit_depth(tmp_path, minimal, extra):
    system = minimal
    if extra == "pushbroom":
        system = tmp_path / "pushbroom.toml"
        system.write_text(MINIMAL + PUSHBROOM)
    src = _write(tmp_path / "in.tif", _edge(bands=2))
    out = tmp_path / "out.tif"
    band = extra.split() if extra.startswith("--band") else []
    r = _sim(src, "--system", system, "--units", "reflectance", "--no-noise", *band, "-o", out)
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as o:
        assert o.dtypes[0] == "float32" and o.count == (1 if band else 2)
        a = o.read(1)
    # the edge's two sides keep their reflectance (no DN range clips or rounds them)
    assert np.nanmedian(a[:, :3]) == pytest.approx(0.2, abs=0.02)
    assert np.nanmedian(a[:, -3:]) == pytest.approx(0.6, abs=0.02)


def test_a_sweep_of_a_system_without_bit_depth_in_reflectance(tmp_path, minimal):
    src = _write(tmp_path / "in.tif", _edge())
    r = _sim(src, "--system", minimal, "--units", "reflectance", "--no-noise", "--sweep", "motion.smear_px=0.5,1",
             "-o", tmp_path / "sw")  # fmt: skip
    assert r.exit_code == 0, r.output
    cases = json.loads((tmp_path / "sw" / "manifest.json").read_text())["cases"]
    assert [c["status"] for c in cases] == ["written", "written"]


# ------------------------------------------------------------------------------ items 3 and 6: float options
@pytest.mark.parametrize("option", ["--scene-pixel-m", "--input-scale"])
@pytest.mark.parametrize("value", ["nan", "inf", "0", "-0.5"])
@pytest.mark.parametrize("suffix", [".tif", ".npy"])
def test_a_scale_that_is_not_finite_and_positive_is_refused_by_name(tmp_path, option, value, suffix):
    if suffix == ".tif":
        src = _write(tmp_path / "in.tif", _edge())
    else:
        src = tmp_path / "in.npy"
        np.save(src, _edge()[0])
    pixel = [] if option == "--scene-pixel-m" or suffix == ".tif" else ["--scene-pixel-m", PX]
    out = tmp_path / "out.tif"
    r = _sim(src, "--preset", "ankarasat3", option, value, *pixel, "-o", out)
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert option in line and "unexpected" not in line and "nodata" not in line
    assert "finite" in line or "must be" in line
    assert not out.exists()


# ----------------------------------------------------------------------------- item 5: contradicting pixel size
@pytest.mark.parametrize("focal_plane", [False, True])
def test_a_pixel_size_that_contradicts_the_files_transform_is_refused(tmp_path, focal_plane):
    src = _write(tmp_path / "in.tif", _edge())
    out = tmp_path / "out.tif"
    fp = ["--focal-plane", tmp_path / "fp.tif"] if focal_plane else []
    r = _sim(src, "--preset", "ankarasat3", "--scene-pixel-m", "0.5", *fp, "-o", out)
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert "--scene-pixel-m" in line and "0.5" in line and "0.07" in line
    assert not out.exists()


def test_a_pixel_size_that_agrees_with_the_files_transform_is_accepted(tmp_path):
    src = _write(tmp_path / "in.tif", _edge())
    out = tmp_path / "out.tif"
    r = _sim(src, "--preset", "ankarasat3", "--scene-pixel-m", "0.07", "--units", "reflectance", "--no-noise",
             "-o", out)  # fmt: skip
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as o:
        system = satchain.load_preset("ankarasat3")
        assert o.transform.a == pytest.approx(system.gsd_act_m, rel=1e-9)


def test_simulate_image_refuses_a_pixel_m_that_contradicts_its_transform():
    system = satchain.load_preset("ankarasat3")
    t = Affine(PX, 0, 5e5, 0, -PX, 4.4e6)
    with pytest.raises(ConfigError, match=r"pixel_m.*0\.5.*0\.07"):
        satchain.simulate_image(_edge()[0], system, pixel_m=0.5, transform=t, noise=False, units="reflectance")
    r = satchain.simulate_image(_edge()[0], system, pixel_m=PX, transform=t, noise=False, units="reflectance")
    assert r.transform.a == pytest.approx(system.gsd_act_m, rel=1e-9)


# --------------------------------------------------------------------- item 4: valid data narrower than a pixel
def test_valid_data_narrower_than_an_output_pixel_is_refused_not_written_as_nodata(tmp_path):
    a = np.zeros((240, 240), np.uint16)
    a[:, 120:123] = 30000  # a 3-px (0.21 m) column: less than one 0.49 m output pixel
    src = _write(tmp_path / "col.tif", a, nodata=0)
    out = tmp_path / "out.tif"
    r = _sim(src, "--preset", "ankarasat3", "-o", out)
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert "nodata" in line and "output pixel" in line and "unexpected" not in line
    assert not out.exists()


# ------------------------------------------------------------------------- item 19: a sweep checks every case
@pytest.mark.parametrize("suffix", [".tif", ".npy"])
def test_a_sweep_whose_later_case_cannot_be_simulated_writes_nothing(tmp_path, suffix):
    if suffix == ".tif":
        src, pixel = _write(tmp_path / "in.tif", _edge()), []
    else:
        src, pixel = tmp_path / "in.npy", ["--scene-pixel-m", PX]
        np.save(src, _edge()[0])
    out = tmp_path / "sweep"
    # case 2: a 1 mm pitch gives an 83 m GSD, larger than the whole 17 m input
    r = _sim(src, "--preset", "ankarasat3", *pixel, "--sweep", "detector.pitch_m=5.88e-6,1e-3", "-o", out)
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert "detector.pitch_m=0.001" in line and "smaller than one detector pixel" in line
    assert not out.exists()  # case 1 was not written: every case is checked first


def test_an_unreachable_scheduler_is_named_not_taken_for_a_file_problem(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    from satchain.engine import distributed

    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT_S", 1.0)
    src = _write(tmp_path / "in.tif", _edge())
    out = tmp_path / "out.tif"
    r = _sim(src, "--preset", "ankarasat3", "--scheduler", "tcp://127.0.0.1:1", "-o", out)  # port 1: nobody listens
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert "tcp://127.0.0.1:1" in line and "cannot reach a Dask scheduler" in line
    assert "disk" not in line and not out.exists()


@pytest.mark.parametrize("where", ["scene", "sweep input", "line of sight"])
def test_a_folder_given_as_a_file_is_called_a_folder_not_missing(tmp_path, where):
    folder = tmp_path / {"scene": "layout.toml", "sweep input": "b.tif", "line of sight": "los.csv"}[where]
    folder.mkdir()
    if where == "scene":
        r = _sim(folder, "--preset", "ankarasat3", "-o", tmp_path / "out.tif")
    elif where == "sweep input":
        r = _sim(_write(tmp_path / "a.tif", _edge()), folder, "--preset", "ankarasat3", "-o", tmp_path / "sw")
    else:
        system = tmp_path / "los.toml"
        system.write_text(MINIMAL + f'[motion.line_of_sight]\nfile = "{folder.name}"\n')
        r = runner.invoke(app, ["budget", "--system", str(system)])
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert folder.name in line and "folder" in line and "no such file" not in line and "not found" not in line


@pytest.mark.parametrize("value", [0.0, float("nan"), -1.0])
def test_simulate_image_refuses_an_input_scale_that_is_not_finite_and_positive(tmp_path, value):
    system = satchain.load_preset("ankarasat3")
    src = _write(tmp_path / "in.tif", _edge())
    for source in (src, _edge()[0]):
        with pytest.raises(ConfigError, match="input_scale"):
            satchain.simulate_image(source, system, pixel_m=PX, input_scale=value)


# ------------------------------------------------------------------------ item 6 follow-up: a scale far too small
@pytest.mark.parametrize("suffix", [".tif", ".npy"])
def test_an_input_scale_that_makes_every_value_darker_than_any_ground_is_refused(tmp_path, suffix):
    dn = np.round(_edge()[0] * 65535).astype(np.uint16)
    src = _write(tmp_path / "in.tif", dn) if suffix == ".tif" else tmp_path / "in.npy"
    if suffix == ".npy":
        np.save(src, dn)
    pixel = ["--scene-pixel-m", PX] if suffix == ".npy" else []
    out = tmp_path / "out.tif"
    r = _sim(src, "--preset", "ankarasat3", "--input-scale=1e-30", *pixel, "-o", out)
    line = " ".join(r.output.split())
    assert r.exit_code == 2 and "--input-scale" in line and "1e-30" in line and "darker" in line, r.output
    assert not out.exists()


def test_a_dark_water_scene_at_a_sensible_scale_is_simulated(tmp_path):
    """Real dark ground (0.02-0.05 reflectance as uint16 x 10000) is far above the rule's 1e-3."""
    dn = np.round((_edge()[0] - 0.2) * 0.075 / 0.4 * 10000 + 200).astype(np.uint16)  # 0.02 .. 0.05
    src = _write(tmp_path / "in.tif", dn)
    r = _sim(src, "--preset", "ankarasat3", "--input-scale", "1e-4", "-o", tmp_path / "out.tif")
    assert r.exit_code == 0, r.output
