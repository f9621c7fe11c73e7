"""Issue 20, point 1: a measured line of sight (``[motion.line_of_sight]``, e.g. from an attitude log, inline or a
CSV file) drives the simulation in time and the budget exactly as the equivalent analytic motion does."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import j0

import satchain
from satchain import load_preset
from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError, SatchainIOError
from satchain.tf.budget import SystemOTF
from satchain.tf.pushbroom import PushbroomTerms

BASE = load_preset("ankarasat3")
DT, N = BASE.line_time_s, BASE.detector.tdi_stages


def _sine_log(freq_hz: float, amp: float, duration_s: float, axis: str = "act", per_period: int = 64) -> dict:
    t = np.arange(0.0, duration_s, 1.0 / (freq_hz * per_period))
    return {"time_s": t.tolist(), f"{axis}_px": (amp * np.sin(2 * np.pi * freq_hz * t)).tolist()}


def _nyquist(system, axis: str = "act") -> float:
    ny = BASE.nyquist_act_cy_per_mm
    f = (np.array([ny]), np.array([0.0])) if axis == "act" else (np.array([0.0]), np.array([ny]))
    return float(np.abs(SystemOTF(system)(*f))[0])


def test_a_csv_log_beside_the_system_file_is_read_and_kept_in_the_system(tmp_path):
    t = np.linspace(0.0, 0.2, 2001)
    rows = "\n".join(f"{a:.9g},{0.3 * math.sin(40 * a):.9g}" for a in t)
    (tmp_path / "logs").mkdir()
    (tmp_path / "logs" / "att.csv").write_text("# attitude log, satchain test\ntime_s,act_px\n" + rows + "\n")
    preset = (satchain.config.system.resources.files("satchain.presets") / "ankarasat3.toml").read_text()
    (tmp_path / "sys.toml").write_text(
        preset + '\n[motion.line_of_sight]\nfile = "logs/att.csv"\ntime_offset_s = 0.01\n'
    )
    s = ImagingSystem.from_toml(tmp_path / "sys.toml")
    log = s.motion.line_of_sight
    assert len(log.time_s) == 2001 and log.alt_px == (0.0,) * 2001 and log.time_offset_s == 0.01
    assert log.act_px[1000] == pytest.approx(0.3 * math.sin(40 * t[1000]), abs=1e-9)
    again = ImagingSystem.from_dict(s.to_dict())  # self-contained: the samples, not the file name
    assert again.motion.line_of_sight == log and "file" not in s.to_dict()["motion"]["line_of_sight"]


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ({"time_s": [0.0, 1.0]}, "needs act_px, alt_px or both"),
        ({"time_s": [0.0, 1.0], "act_px": [0.0]}, "act_px has 1 values but time_s has 2"),
        ({"time_s": [0.0, 0.0], "act_px": [0.0, 1.0]}, "time_s: must be finite and strictly increasing"),
        ({"time_s": [0.0, 1.0], "act_px": [0.0, float("nan")]}, "act_px.*finite"),
        ({"file": "x.csv", "time_s": [0.0, 1.0]}, "either file or time_s"),
    ],
)
def test_bad_logs_are_refused_naming_the_key(table, match, tmp_path):
    if "file" in table:
        (tmp_path / "x.csv").write_text("time_s,act_px\n0,0\n1,1\n")
        table = {**table, "file": str(tmp_path / "x.csv")}
    with pytest.raises(ConfigError, match=match):
        BASE.replace({"motion.line_of_sight": table})


def test_bad_log_files_are_refused(tmp_path):
    with pytest.raises(SatchainIOError, match="not found"):
        BASE.replace({"motion.line_of_sight": {"file": str(tmp_path / "none.csv")}})
    (tmp_path / "h.csv").write_text("t,x\n0,0\n1,1\n")
    with pytest.raises(ConfigError, match="need time_s and act_px and/or alt_px"):
        BASE.replace({"motion.line_of_sight": {"file": str(tmp_path / "h.csv")}})


def test_the_budget_of_a_logged_whole_cycle_oscillation_is_j0():
    f = 5 / (N * DT)
    s = BASE.replace({"motion.line_of_sight": _sine_log(f, 0.5, 0.05)})
    assert _nyquist(s) == pytest.approx(_nyquist(BASE) * float(j0(math.pi / 2)), abs=0.003)


@pytest.mark.parametrize("axis", ["act", "alt"])
def test_a_logged_oscillation_budgets_and_images_as_the_analytic_one(axis):
    """1.3 cycles per window: the phase-averaged exact form and its geometry; the simulated rows too."""
    f = 1.3 / (N * DT)
    osc = BASE.replace({"motion.oscillation": [{"axis": axis, "amplitude_px": 0.5, "frequency_hz": f}]})
    logged = BASE.replace({"motion.line_of_sight": _sine_log(f, 0.5, 0.3, axis)})
    assert _nyquist(logged, axis) == pytest.approx(_nyquist(osc, axis), abs=1e-3)
    g_o, g_l = PushbroomTerms(osc).geometry(), PushbroomTerms(logged).geometry()
    for key in ("line_displacement_rms_px", "line_to_line_rms_px"):
        assert g_l[key][axis] == pytest.approx(g_o[key][axis], rel=0.01)
    y, x = np.mgrid[0:700, 0:700] + 0.5
    scene = 0.4 + 0.3 * np.sin(2 * np.pi * (x / 23.0 + y / 31.0))
    a = satchain.simulate_image(scene, osc, pixel_m=0.07).image
    b = satchain.simulate_image(scene, logged, pixel_m=0.07).image
    assert np.max(np.abs(a - b)) < 1e-3


def test_a_log_shorter_than_the_scan_is_refused():
    s = BASE.replace({"motion.line_of_sight": _sine_log(100.0, 0.5, 30 * DT)})  # 30 lines of log
    with pytest.raises(ConfigError, match="line_of_sight: the log covers .* the scan needs"):
        satchain.simulate_image(np.full((700, 700), 0.5), s, pixel_m=0.07)
