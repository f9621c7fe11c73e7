"""ImagingSystem: validation naming key/value/range, TOML round trip, derived quantities."""

import math

import numpy as np
import pytest

from satchain import ConfigError, ImagingSystem, SatchainIOError, load_preset, load_system
from satchain.config.system import EARTH_GM_M3_PER_S2, EARTH_RADIUS_M, preset_names

BASE = {
    "orbit": {"altitude_m": 500e3},
    "optics": {"aperture_diameter_m": 0.5, "f_number": 10.0, "wavelengths_m": [5e-7, 7e-7]},
    "detector": {"pitch_m": 5e-6},
}


def make(**over):
    d = {k: dict(v) for k, v in BASE.items()}
    for key, v in over.items():
        sec, _, field = key.partition("__")
        if v is None:
            d[sec].pop(field, None)
        else:
            d[sec][field] = v
    return ImagingSystem.from_dict(d)


def test_reference_derived_quantities(ankarasat3):
    s = ankarasat3
    assert s.focal_length_m == pytest.approx(6.804)
    assert s.gsd_act_m == pytest.approx(0.49) and s.gsd_alt_m == pytest.approx(0.49)
    assert s.ifov_alt_rad == pytest.approx(5.88e-6 / 6.804)
    assert s.nyquist_alt_cy_per_mm == pytest.approx(85.034, abs=1e-3)
    assert s.nyquist_alt_cy_per_m_ground == pytest.approx(1 / 0.98)
    lam = s.optics.wavelengths_m[0]
    assert s.optical_cutoff_cy_per_mm[0] == pytest.approx(1 / (lam * 9.72 * 1e3))
    assert s.q_effective == pytest.approx(lam * 9.72 / 5.88e-6)
    assert s.airy_diameter_m[0] == pytest.approx(2.43934 * lam * 9.72, rel=1e-5)
    assert s.limited_by == "detector"


def test_limited_by_follows_q():
    coarse_optics = make(optics__f_number=30.0)  # Q = 0.6um*30/5um = 3.6 > 2
    assert coarse_optics.limited_by == "optics"
    assert make().limited_by == "detector"  # Q = 1.2


def test_polychromatic_effective_wavelength_and_weights():
    s = make(optics__wavelength_weights=[1.0, 3.0])
    np.testing.assert_allclose(s.optics.weights, [0.25, 0.75])
    assert s.optics.effective_wavelength_m == pytest.approx(0.25 * 5e-7 + 0.75 * 7e-7)
    assert make().optics.effective_wavelength_m == pytest.approx(6e-7)


def test_focal_length_or_f_number():
    a = make(optics__f_number=None, optics__focal_length_m=5.0)
    assert a.f_number == pytest.approx(10.0)
    b = make(optics__focal_length_m=5.0)  # consistent with f/10 and D = 0.5
    assert b.focal_length_m == pytest.approx(5.0)
    with pytest.raises(ConfigError, match="focal_length_m = 4.0 and optics.f_number = 10.0 disagree"):
        make(optics__focal_length_m=4.0)
    with pytest.raises(ConfigError, match="give optics.focal_length_m or optics.f_number"):
        make(optics__f_number=None)


def test_rectangular_pixels_and_fill_factor():
    s = make(detector__pitch_m=None, detector__pitch_x_m=4e-6, detector__pitch_y_m=8e-6, detector__fill_factor=0.64)
    assert s.gsd_act_m == pytest.approx(4e-6 * 500e3 / 5.0)
    assert s.gsd_alt_m == pytest.approx(2 * s.gsd_act_m)
    assert s.gsd_m == pytest.approx(math.sqrt(s.gsd_act_m * s.gsd_alt_m))
    assert s.detector.active_width_x_m == pytest.approx(0.8 * 4e-6)
    assert s.detector.fill_factor == pytest.approx(0.64)


@pytest.mark.parametrize(
    ("over", "message"),
    [
        ({"optics__obscuration_ratio": 1.2}, r"optics\.obscuration_ratio = 1\.2: .*less than 1"),
        ({"orbit__altitude_m": -5.0}, r"orbit\.altitude_m = -5\.0: .*greater than 0"),
        ({"detector__fill_factor": 1.5}, r"detector\.fill_factor = 1\.5: must be in \(0, 1\]"),
        ({"optics__wavelengths_m": [5e-7, 3.0]}, r"wavelengths_m\[1\] = 3\.0: must be in"),
        ({"optics__wavelength_weights": [1.0]}, r"wavelength_weights has 1 entries but wavelengths_m has 2"),
        ({"optics__transmission": 0.0}, r"optics\.transmission = 0\.0"),
        ({"optics__zernike_rms_waves": {"99": 0.1}}, r"Noll index must be in \[1, 66\]"),
        ({"optics__spelling_mistake": 1}, r"optics\.spelling_mistake: unknown key"),
        ({"detector__active_width_x_m": 6e-6}, r"active_width_x_m = 6e-06: must be <= pitch_x_m"),
        ({"detector__tdi_stages": 0}, r"detector\.tdi_stages = 0"),
    ],
)
def test_invalid_values_name_key_value_and_range(over, message):
    with pytest.raises(ConfigError, match=message):
        make(**over)


def test_missing_section_is_named():
    with pytest.raises(ConfigError, match="detector: required key is missing"):
        ImagingSystem.from_dict({"orbit": BASE["orbit"], "optics": BASE["optics"]})


def test_errors_are_value_errors():
    with pytest.raises(ValueError):
        make(optics__obscuration_ratio=-0.1)


def test_frozen(ankarasat3):
    with pytest.raises(Exception, match="frozen"):
        ankarasat3.optics.obscuration_ratio = 0.1  # type: ignore[misc]


def test_toml_round_trip(tmp_path, ankarasat3):
    import tomllib

    text = [
        "[orbit]",
        "altitude_m = 567000.0",
        "[optics]",
        "aperture_diameter_m = 0.7",
        "focal_length_m = 6.804",
        "wavelengths_m = [6.5e-7]",
        "obscuration_ratio = 0.3",
        "[detector]",
        "pitch_m = 5.88e-6",
        "[motion]",
        "smear_px = 1.0",
    ]
    p = tmp_path / "s.toml"
    p.write_text("\n".join(text))
    s = load_system(p)
    assert s.f_number == pytest.approx(9.72)
    assert s.gsd_alt_m == pytest.approx(ankarasat3.gsd_alt_m)
    # to_dict() is valid input again and reproduces the same system
    assert ImagingSystem.from_dict(s.to_dict()) == s
    assert tomllib.loads("\n".join(text))["optics"]["focal_length_m"] == 6.804


def test_bad_files(tmp_path):
    with pytest.raises(SatchainIOError, match="not found"):
        load_system(tmp_path / "nope.toml")
    p = tmp_path / "bad.toml"
    p.write_text("[orbit\naltitude_m = 1")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_system(p)
    with pytest.raises(ConfigError, match="preset = 'nosuch': must be one of 'ankarasat3'"):
        load_preset("nosuch")


def test_replace_validates_and_keeps_fill(ankarasat3):
    s = ankarasat3.replace({"optics.obscuration_ratio": 0.1, "detector.pitch_m": 4e-6, "optics.wavelength_m": 5e-7})
    assert s.optics.obscuration_ratio == 0.1
    assert s.detector.pitch_x_m == 4e-6 and s.detector.fill_factor == pytest.approx(1.0)
    assert s.optics.wavelengths_m == (5e-7,)
    assert s.replace({"optics.f_number": 5.0}).focal_length_m == pytest.approx(3.5)
    with pytest.raises(ConfigError, match="obscuration_ratio = 1.5"):
        ankarasat3.replace({"optics.obscuration_ratio": 1.5})
    with pytest.raises(ConfigError, match="optics has no field 'colour'"):
        ankarasat3.replace({"optics.colour": 1})


def test_orbit_speeds():
    s = make()
    r = EARTH_RADIUS_M + 500e3
    assert s.orbit.orbital_speed_m_per_s == pytest.approx(math.sqrt(EARTH_GM_M3_PER_S2 / r))
    assert s.orbit.ground_speed_m_per_s == pytest.approx(7613 * EARTH_RADIUS_M / r, rel=2e-3)


def test_presets_listed():
    assert "ankarasat3" in preset_names()
