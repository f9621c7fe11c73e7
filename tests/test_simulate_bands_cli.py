"""``satchain simulate`` with a banded system (``[[bands]]`` with spectral responses) and a scene layout: every band
formed from the spectral scene, one GeoTIFF per pixel grid (pan.tif, ms.tif) and the RGB / false-colour previews.

The MS values on flat patches are checked against the materials' own spectra (USGS splib07 sea water, PROSAIL
vegetation) averaged over the issue's band limits (450-520, 760-900 nm, ...) here, independently of the code under
test's band integration; a single-band system keeps today's single-file output.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rasterio
from PIL import Image
from typer.testing import CliRunner

from satchain import load_preset
from satchain.cli.main import app

runner = CliRunner()

#: the issue's band limits (nm) of the ankarasat3-pms MS bands
LIMITS_NM = {"blue": (450, 520), "green": (520, 600), "red": (630, 690), "nir": (760, 900)}

SCENE = """
[scene]
width_m = 32.0
height_m = 32.0
pixel_m = 0.245
background_material = "dry_grass"

[[items]]
kind = "slanted_edge"
id = "edge"
center_m = [16.0, 16.0]
size_m = 32.0
angle_deg = 5.0
measures = "act"
bright_material = "{bright}"
dark_material = "water"
"""


def _write_scene(path: Path, bright: str = "green_vegetation") -> Path:
    path.write_text(SCENE.format(bright=bright))
    return path


@pytest.fixture(scope="module")
def banded(tmp_path_factory):
    """One noise-free banded simulation in reflectance: (scene file, output directory, CLI output)."""
    d = tmp_path_factory.mktemp("banded")
    scene = _write_scene(d / "scene.toml")
    out = d / "out"
    r = runner.invoke(app, ["simulate", str(scene), "--preset", "ankarasat3-pms", "--units", "reflectance",
                            "--no-noise", "-o", str(out)])  # fmt: skip
    assert r.exit_code == 0, r.output
    return scene, out, r.output


def _spectrum_mean(name: str, band: str) -> float:
    from satchain.scene.materials import material

    m = material(name)
    lam = np.asarray(m.wavelengths_m) * 1e9
    lo, hi = LIMITS_NM[band]
    return float(np.asarray(m.reflectance)[(lam >= lo) & (lam <= hi)].mean())


def test_rasters_and_previews_written_with_band_metadata_and_georeference(banded, tmp_path):
    scene, out, output = banded
    assert sorted(p.name for p in out.iterdir()) == ["false_colour.png", "ms.tif", "pan.tif", "rgb.png"]
    assert "pan.tif" in output and "ms.tif" in output
    system = load_preset("ankarasat3-pms")
    # today's single-band output of the same scene: its georeference is the one to keep
    ref = tmp_path / "today.tif"
    r = runner.invoke(app, ["simulate", str(scene), "--preset", "ankarasat3", "--units", "reflectance", "--no-noise",
                            "-o", str(ref)])  # fmt: skip
    assert r.exit_code == 0, r.output
    with rasterio.open(ref) as f:
        t_ref, shape_ref = f.transform, f.shape
    with rasterio.open(out / "pan.tif") as f:
        assert f.count == 1 and f.descriptions == ("pan",)
        assert f.res == pytest.approx((0.49, 0.49))
        assert f.transform.almost_equals(t_ref) and f.shape == shape_ref
        assert float(f.tags(1)["center_wavelength_m"]) == pytest.approx(system.bands[0].center_wavelength_m)
    with rasterio.open(out / "ms.tif") as f:
        assert f.count == 4 and f.descriptions == ("blue", "green", "red", "nir")
        assert f.res == pytest.approx((1.96, 1.96))  # 4x the PAN pixel
        assert (f.transform.c, f.transform.f) == pytest.approx((t_ref.c, t_ref.f))  # the same corner
        assert f.shape == (shape_ref[0] // 4, shape_ref[1] // 4)
        for i, name in enumerate(("blue", "green", "red", "nir"), start=1):
            lam = float(f.tags(i)["center_wavelength_m"])
            assert lam == pytest.approx(system.bands[i].center_wavelength_m)
            lo, hi = LIMITS_NM[name]
            assert lo * 1e-9 < lam < hi * 1e-9
            assert float(f.tags(i, ns="IMAGERY")["CENTRAL_WAVELENGTH_UM"]) == pytest.approx(lam * 1e6, rel=1e-5)
        ms_shape = f.shape
    for png in ("rgb.png", "false_colour.png"):
        with Image.open(out / png) as im:
            assert im.mode == "RGB" and im.size == (ms_shape[1], ms_shape[0])


def test_ms_values_on_flat_patches_follow_the_material_spectra(banded):
    _, out, _ = banded
    with rasterio.open(out / "ms.tif") as f:
        ms = {name: f.read(i) for i, name in enumerate(f.descriptions, start=1)}
    # the edge (x = 16 m +- 1.4 m over its length) splits water (left, dark side) from vegetation (right)
    water = {k: float(v[2:14, 1:5].mean()) for k, v in ms.items()}
    veg = {k: float(v[2:14, 11:15].mean()) for k, v in ms.items()}
    assert veg["nir"] > 5 * veg["red"]  # the red edge: chlorophyll absorbs red, leaves scatter NIR
    assert veg["green"] > veg["red"] and veg["green"] > veg["blue"]
    assert water["blue"] > water["nir"]  # water absorbs NIR
    for name in LIMITS_NM:  # each band the spectrum's mean over its limits (Gaussian vs boxcar weights)
        assert water[name] == pytest.approx(_spectrum_mean("water", name), rel=0.06, abs=0.005)
        assert veg[name] == pytest.approx(_spectrum_mean("green_vegetation", name), rel=0.06, abs=0.005)


def test_one_band_into_an_earlier_output_replaces_it(banded, tmp_path):
    import shutil

    scene, out, _ = banded
    again = tmp_path / "again"
    shutil.copytree(out, again)
    r = runner.invoke(app, ["simulate", str(scene), "--preset", "ankarasat3-pms", "--band", "5", "--units",
                            "reflectance", "--no-noise", "-o", str(again)])  # fmt: skip
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in again.iterdir()) == ["nir.tif"]  # the earlier files not written now: removed
    with rasterio.open(again / "nir.tif") as a, rasterio.open(out / "ms.tif") as b:
        assert a.descriptions == ("nir",) and a.transform == b.transform
        np.testing.assert_allclose(a.read(1), b.read(4), atol=1e-6)  # the same band, formed alone


def test_single_band_system_and_grey_layout_give_todays_output(tmp_path):
    from satchain.engine.files import simulate_file

    scene = tmp_path / "grey.toml"
    scene.write_text(SCENE.replace('background_material = "dry_grass"', "background = 0.2")
                     .replace('bright_material = "{bright}"', "bright = 0.6").replace('dark_material = "water"',
                                                                                       "dark = 0.05"))  # fmt: skip
    r = runner.invoke(app, ["simulate", str(scene), "--preset", "ankarasat3", "--seed", "3", "-o",
                            str(tmp_path / "cli.tif")])  # fmt: skip
    assert r.exit_code == 0, r.output
    simulate_file(str(scene), tmp_path / "direct.tif", load_preset("ankarasat3"), seed=3)
    with rasterio.open(tmp_path / "cli.tif") as a, rasterio.open(tmp_path / "direct.tif") as b:
        assert a.count == 1 and a.transform == b.transform
        np.testing.assert_array_equal(a.read(), b.read())


def _refused(args: list[str], *needles: str) -> str:
    r = runner.invoke(app, ["simulate", *args])
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert "Traceback" not in r.output
    for n in needles:
        assert n in line, line
    return line


def test_unknown_material_refused_nothing_written(tmp_path):
    scene = _write_scene(tmp_path / "bad.toml", bright="unobtainium")
    _refused([str(scene), "--preset", "ankarasat3-pms", "-o", str(tmp_path / "out")], "unobtainium", "asphalt")
    assert not (tmp_path / "out").exists()


def test_band_name_clash_refused(tmp_path):
    text = (Path(__file__).parents[1] / "src/satchain/presets/ankarasat3-pms.toml").read_text()
    assert text.count('name = "blue"') == 1
    system = tmp_path / "clash.toml"
    system.write_text(text.replace('name = "blue"', 'name = "red"'))
    scene = _write_scene(tmp_path / "s.toml")
    _refused([str(scene), "--system", str(system), "-o", str(tmp_path / "out")], "red")
    assert not (tmp_path / "out").exists()


def test_output_directory_with_other_files_or_a_file_path_refused(tmp_path):
    scene = _write_scene(tmp_path / "s.toml")
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    _refused([str(scene), "--preset", "ankarasat3-pms", "-o", str(out)], "notes.txt")
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]
    _refused([str(scene), "--preset", "ankarasat3-pms", "-o", str(tmp_path / "image.tif")], "directory")
    assert not (tmp_path / "image.tif").exists()


def test_raster_with_another_band_count_refused_naming_both(tmp_path):
    img = tmp_path / "two.tif"
    with rasterio.open(img, "w", driver="GTiff", width=64, height=64, count=2, dtype="float32",
                       transform=rasterio.Affine(0.245, 0, 0, 0, -0.245, 0)) as f:  # fmt: skip
        f.write(np.full((2, 64, 64), 0.3, dtype="float32"))
    _refused([str(img), "--preset", "ankarasat3-pms", "-o", str(tmp_path / "o.tif")], "2 bands", "5")
    assert not (tmp_path / "o.tif").exists()
