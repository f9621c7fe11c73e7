"""Issue 20's acceptance through the command line: `satchain simulate` of 5 deg edges at a 0.07 m scene pixel
(noise-free reflectance) with pushbroom motion keys in a system file, measured by `satchain measure edge`, against
`satchain budget` and the closed forms."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import rasterio
from rasterio import Affine
from scipy.special import j0
from typer.testing import CliRunner

from satchain import load_preset
from satchain.cli.main import app

runner = CliRunner()
BASE = load_preset("ankarasat3")
PX, N_IN = 0.07, 1400
T5 = math.tan(math.radians(5.0))


def _edges(path, kind: str):
    y, x = np.mgrid[0:N_IN, 0:N_IN] + 0.5
    if kind == "vertical":
        a = np.where(x - (N_IN / 2 + (y - N_IN / 2) * T5) > 0, 0.6, 0.2)
    else:
        a = np.where(y - (N_IN / 2 + (x - N_IN / 2) * T5) > 0, 0.6, 0.2)
    with rasterio.open(path, "w", driver="GTiff", width=N_IN, height=N_IN, count=1, dtype="float32",
                       crs="EPSG:32636", transform=Affine(PX, 0, 5e5, 0, -PX, 4e6)) as d:  # fmt: skip
        d.write(a.astype(np.float32), 1)
    return path


def _system_file(tmp_path, extra: str):
    from importlib import resources

    text = resources.files("satchain.presets").joinpath("ankarasat3.toml").read_text()
    text = text.replace("[orbit]\naltitude_m = 567000.0", "[orbit]\naltitude_m = 567000.0\n" + extra.split("##")[0])
    p = tmp_path / "sys.toml"
    p.write_text(text + ("\n" + extra.split("##")[1] if "##" in extra else ""))
    return p


def _measure(tmp_path, system, kind: str) -> dict:
    src = _edges(tmp_path / f"{kind}.tif", kind)
    out = tmp_path / f"{kind}_sim.tif"
    r = runner.invoke(app, ["simulate", str(src), "--system", str(system), "--units", "reflectance", "--no-noise",
                            "-o", str(out)])  # fmt: skip
    assert r.exit_code == 0, r.output
    roi = "70,30,130,170" if kind == "vertical" else "30,70,170,130"
    r = runner.invoke(app, ["measure", "edge", str(out), "--roi", roi, "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def test_an_act_oscillation_with_whole_cycles_blurs_by_j0_in_budget_and_image(tmp_path):
    f = 5 / (BASE.detector.tdi_stages * BASE.line_time_s)
    sysf = _system_file(tmp_path, f'##[[motion.oscillation]]\naxis = "act"\namplitude_px = 0.5\nfrequency_hz = {f!r}\n')
    from satchain import load_system
    from satchain.tf.budget import SystemOTF

    s = load_system(sysf)
    ny = np.array([s.nyquist_act_cy_per_mm])
    budget = float(np.abs(SystemOTF(s)(ny, np.array([0.0])))[0])
    base = float(np.abs(SystemOTF(BASE)(ny, np.array([0.0])))[0])
    assert budget == pytest.approx(base * j0(math.pi / 2), abs=0.003)
    assert _measure(tmp_path, sysf, "vertical")["mtf_at_nyquist"] == pytest.approx(budget, abs=0.02)


def test_earth_rotation_shears_the_edges_by_the_documented_angles(tmp_path):
    sysf = _system_file(tmp_path, "latitude_deg = 0.0\ninclination_deg = 97.6\nearth_rotation = true\n")
    from satchain import load_system
    from satchain.tf.pushbroom import PushbroomTerms

    g = PushbroomTerms(load_system(sysf)).geometry()
    sig, e = g["shear_act_px_per_line"], g["alt_scale"] - 1.0
    v, h = _measure(tmp_path, sysf, "vertical"), _measure(tmp_path, sysf, "horizontal")
    assert v["angle_deg"] == pytest.approx(math.degrees(math.atan((1 + e) * T5 - sig)), abs=0.05)
    assert 90 - h["angle_deg"] == pytest.approx(math.degrees(math.atan(T5 / (1 + e - sig * T5))), abs=0.05)
