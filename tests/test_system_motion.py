"""The pushbroom motion keys of a system file ([[motion.oscillation]], [motion.jitter_psd],
motion.line_rate_error, the [orbit] Earth-rotation keys): validated with one-line errors naming the key,
round-tripped through TOML, and reachable by ImagingSystem.replace (sweeps)."""

from __future__ import annotations

import pytest

from satchain import load_preset
from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError

BASE = load_preset("ankarasat3")
OSC = {"axis": "act", "amplitude_px": 0.5, "frequency_hz": 4465.0, "phase_deg": 30.0}
PSD = {"axis": "act", "frequency_hz": [5000.0, 50000.0], "psd_px2_per_hz": [3.6e-6, 3.6e-6]}
P = "motion.jitter_psd[0]"
J, ER, LR = "motion.jitter_psd", "orbit.earth_rotation", "motion.line_rate_error"
EARTH = {"orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True}


@pytest.mark.parametrize(
    "values, needle",
    [
        ({"motion.oscillation": [OSC | {"amplitude_px": -1.0}]}, "motion.oscillation[0].amplitude_px = -1.0"),
        ({"motion.oscillation": [OSC | {"amplitude_px": float("nan")}]}, "motion.oscillation[0].amplitude_px = nan"),
        ({"motion.oscillation": [OSC, OSC | {"frequency_hz": 0.0}]}, "motion.oscillation[1].frequency_hz = 0.0"),
        ({"motion.oscillation": [OSC | {"frequency_hz": -5.0}]}, "motion.oscillation[0].frequency_hz = -5.0"),
        ({"motion.oscillation": [OSC | {"frequency_hz": 2e6}]}, "motion.oscillation[0].frequency_hz = 2000000.0"),
        ({"motion.oscillation": [OSC | {"axis": "x"}]}, "motion.oscillation[0].axis = 'x'"),
        ({"motion.oscillation": [OSC | {"phase": 3}]}, "motion.oscillation[0].phase: unknown key"),
        ({J: PSD | {"frequency_hz": [5e4, 5e3]}}, f"{P}.frequency_hz = [50000.0, 5000.0]: must be"),
        ({J: PSD | {"frequency_hz": [5e3, 5e3]}}, "strictly increasing"),
        ({J: PSD | {"frequency_hz": [0.0, 5e3]}}, f"{P}.frequency_hz = [0.0, 5000.0]: must lie in (0, 1e+06]"),
        ({J: PSD | {"psd_px2_per_hz": [1e-6]}}, "motion.jitter_psd[0].psd_px2_per_hz"),
        ({J: PSD | {"psd_px2_per_hz": [1e-6] * 3}}, "psd_px2_per_hz has 3 values but frequency_hz has 2"),
        ({J: PSD | {"psd_px2_per_hz": [1e-6, -1e-6]}}, f"{P}.psd_px2_per_hz = [1e-06, -1e-06]: must be >= 0"),
        ({J: PSD | {"psd_px2_per_hz": [1e-6, float("nan")]}}, "motion.jitter_psd[0].psd_px2_per_hz"),
        ({"motion.line_rate_error": float("nan")}, "motion.line_rate_error = nan"),
        ({"motion.line_rate_error": 0.7}, "motion.line_rate_error = 0.7"),
        ({ER: True, "orbit.inclination_deg": 97.6}, "earth_rotation = true needs orbit.latitude_deg"),
        ({ER: True, "orbit.latitude_deg": 10.0}, "earth_rotation = true needs orbit.inclination_deg"),
        (EARTH | {"orbit.latitude_deg": 85.0}, "orbit.latitude_deg = 85.0: an orbit of inclination 97.6 deg reaches"),
        ({"orbit.yaw_steering": True}, "orbit.yaw_steering = true needs orbit.earth_rotation = true"),
        ({"orbit.earth_rotation": 1}, "orbit.earth_rotation = 1: must be true or false"),
        ({"orbit.inclination_deg": 181.0}, "orbit.inclination_deg = 181.0"),
        ({"orbit.pass_direction": "north"}, "orbit.pass_direction = 'north'"),
        ({LR: 0.05, "detector.tdi_sync_error": 0.01}, "tdi_sync_error = 0.01 and motion.line_rate_error"),
    ],
)  # fmt: skip
def test_bad_keys_are_one_line_errors_naming_the_key(values, needle):
    with pytest.raises(ConfigError) as info:
        BASE.replace(values)
    msg = str(info.value)
    assert needle in msg and "\n" not in msg


def test_toml_round_trip_and_single_table(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(
        "[orbit]\naltitude_m = 567000.0\nlatitude_deg = 0.0\ninclination_deg = 97.6\nearth_rotation = true\n"
        "[optics]\naperture_diameter_m = 0.7\nf_number = 9.72\nwavelengths_m = [6.5e-7]\n"
        "[detector]\npitch_m = 5.88e-6\ntdi_stages = 16\n"
        "[motion]\nline_rate_error = 0.05\n"
        '[[motion.oscillation]]\naxis = "act"\namplitude_px = 0.5\nfrequency_hz = 4465.0\nphase_deg = 30.0\n'
        '[[motion.oscillation]]\naxis = "alt"\namplitude_px = 2.0\nfrequency_hz = 20.0\n'
        '[motion.jitter_psd]\naxis = "act"\nfrequency_hz = [5000.0, 50000.0]\npsd_px2_per_hz = [3.6e-6, 3.6e-6]\n'
    )
    s = ImagingSystem.from_toml(p)
    assert [o.axis for o in s.motion.oscillation] == ["act", "alt"] and len(s.motion.jitter_psd) == 1
    assert s.motion.jitter_psd[0].variance_px2 == pytest.approx(0.162)
    assert ImagingSystem.from_dict(s.to_dict()) == s


def test_replace_reaches_the_new_keys():
    s = BASE.replace({"motion.line_rate_error": 0.05})
    assert s.motion.line_rate_error == 0.05
    s = s.replace({"motion.oscillation": [OSC]}).replace({"motion.oscillation[0].amplitude_px": 2.0})
    assert s.motion.oscillation[0].amplitude_px == 2.0 and s.motion.oscillation[0].phase_deg == 30.0
    s = s.replace({"motion.jitter_psd": PSD}).replace({"motion.jitter_psd[0].psd_px2_per_hz": [1e-6, 2e-6]})
    assert s.motion.jitter_psd[0].psd_px2_per_hz == (1e-6, 2e-6)
    assert s.replace(EARTH).orbit.earth_rotation is True
    with pytest.raises(ConfigError, match=r"index 3 is beyond the 1 entries"):
        s.replace({"motion.oscillation[3].amplitude_px": 1.0})


def test_readme_block_is_valid(tmp_path, monkeypatch):
    import re
    import sys
    from pathlib import Path

    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    text = (Path(__file__).resolve().parents[1] / "docs" / "guide" / "pushbroom.md").read_text()
    (block,) = [b for b in re.findall(r"```toml\n(.*?)```", text, re.S) if "[[motion.oscillation]]" in b]
    keys = tomllib.loads(block)
    monkeypatch.chdir(tmp_path)  # the block's attitude log, relative to the working folder here
    (tmp_path / keys["motion"]["line_of_sight"]["file"]).write_text("time_s,act_px,alt_px\n0,0,0\n1,0.5,-0.2\n")
    d = BASE.to_dict()
    d["motion"].update(keys["motion"])
    d["orbit"].update(keys["orbit"])
    s = ImagingSystem.from_dict(d)
    assert s.motion.oscillation[0].frequency_hz == 4465.0 and s.orbit.inclination_deg == 97.6
