"""Issue 11, point 8: the guide's example system file (docs/guide/budget.md) runs through `simulate` and `run`, and a
run is reproduced from its own config.toml (from any directory): the same simulated image, pixel for pixel."""

import re
from pathlib import Path

import numpy as np
import tomllib
from typer.testing import CliRunner

from satchain._safety import MARKER
from satchain.cli.main import app
from satchain.config.run import RunConfig
from satchain.io import images as io

runner = CliRunner()
BUDGET = Path(__file__).resolve().parents[1] / "docs" / "guide" / "budget.md"



def _readme_system() -> str:
    """The system file of docs/guide/budget.md ("A system file"), written there by ``cat > mycamera.toml``."""
    section = BUDGET.read_text().split("### A system file", 1)[1]
    return re.search(r"^cat > mycamera\.toml <<'EOF'\n(.*?)^EOF$", section, re.S | re.M).group(1)


def test_readme_system_file_simulates_to_dn_within_the_adc_range(tmp_path):
    """No full well stated: the ADC range spans reflectance 0..1, so the paper scene (reflectance < 1) maps
    inside 0..4095 without saturating, and a brighter target gives more DN."""
    (tmp_path / "mycamera.toml").write_text(_readme_system())
    out = tmp_path / "s.tif"
    args = ["simulate", "paper", "--system", str(tmp_path / "mycamera.toml"), "--scene-pixel-m", "0.25"]
    r = runner.invoke(app, [*args, "--no-noise", "-o", str(out)])
    assert r.exit_code == 0, r.output
    img, meta = io.read_image(out)
    assert meta["bit_depth"] == 12 and img.dtype == np.uint16
    assert 0 < img.min() < img.max() < 4095


def test_run_with_readme_system_is_reproduced_from_its_config_toml(tmp_path, monkeypatch, tiny_scene_toml):
    work = tmp_path / "work"
    work.mkdir()
    (work / "mycamera.toml").write_text(_readme_system())
    (work / "tiny.toml").write_text(tiny_scene_toml)
    (work / "run.toml").write_text(
        '[system]\nfile = "mycamera.toml"\n[scene]\nlayout = "tiny.toml"\npixel_m = 0.07\n[simulation]\nseed = 5\n'
    )
    monkeypatch.chdir(work)
    r = runner.invoke(app, ["run", "--config", "run.toml", "-o", "first"])
    assert r.exit_code == 0, r.output
    first = work / "first"
    assert (first / MARKER).is_file()
    saved = tomllib.loads((first / "config.toml").read_text())
    assert saved["system"] == {"file": str(work / "mycamera.toml")}  # absolute, and no preset beside it
    assert Path(saved["scene"]["layout"]).is_absolute()
    # from elsewhere, with only the run's own config.toml
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    r = runner.invoke(app, ["run", "--config", str(first / "config.toml"), "-o", "again"])
    assert r.exit_code == 0, r.output
    a, meta_a = io.read_image(first / "images" / "simulated.tif")
    b, _ = io.read_image(elsewhere / "again" / "images" / "simulated.tif")
    np.testing.assert_array_equal(a, b)
    assert meta_a["bit_depth"] == 12 and a.dtype == np.uint16  # run writes through the camera's bit depth


def test_config_never_holds_both_preset_and_file(tmp_path):
    import pytest

    from satchain.errors import ConfigError

    with pytest.raises(ConfigError, match="preset and file"):
        RunConfig.from_dict({"system": {"preset": "ankarasat3", "file": "x.toml"}})
    cfg = RunConfig.from_dict({"system": {"file": "x.toml"}}, base_dir=tmp_path)
    assert cfg.system.preset is None and cfg.to_dict()["system"] == {"file": "x.toml"}
    assert RunConfig().system.preset == "ankarasat3"
