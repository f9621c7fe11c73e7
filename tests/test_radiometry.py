"""Radiometry: closed forms (Planck / Stefan-Boltzmann, Lambert, camera equation), unit round trips,
noise adding in quadrature, CCD vs CMOS TDI accumulation, saturation, configuration errors."""

from __future__ import annotations

import json
import math
from importlib import resources

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain import ConfigError, ImagingSystem, InputError
from satchain import radiometry as rad

H, C, SIGMA = 6.62607015e-34, 299792458.0, 5.670374419e-8  # CODATA 2018 (exact h, c)
R_SUN, AU = 6.957e8, 1.495978707e11

MINIMAL = {
    "orbit": {"altitude_m": 500e3},
    "optics": {"aperture_diameter_m": 0.5, "f_number": 10.0, "wavelengths_m": [6e-7]},
    "detector": {"pitch_m": 10e-6},
}


def _system(**sections) -> ImagingSystem:
    d = {k: dict(v) for k, v in MINIMAL.items()}
    for sec, values in sections.items():
        d.setdefault(sec, {}).update(values)
    return ImagingSystem.from_dict(d)


def _table():
    """The shipped data file read independently of satchain.radiometry (nm, W m^-2 nm^-1)."""
    with (resources.files("satchain") / "data" / "astm_g173_etr.csv").open() as fh:
        text = fh.read()
    rows = [ln.split(",") for ln in text.splitlines() if ln and not ln.startswith("#")]
    return text, np.array(rows, dtype=float)


# ---------------------------------------------------------------- the sun
@pytest.mark.parametrize("t_k", [300.0, 1000.0, 5778.0])
def test_planck_integral_is_stefan_boltzmann(t_k):
    lam = np.geomspace(1e-8, 1e-2, 400001)
    total = np.trapezoid(rad.planck_spectral_radiance(lam, t_k), lam)
    assert total == pytest.approx(SIGMA * t_k**4 / math.pi, rel=1e-5)


def test_planck_peak_is_wien():
    lam = np.linspace(3e-7, 8e-7, 50001)
    peak = lam[np.argmax(rad.planck_spectral_radiance(lam, 5778.0))]
    assert peak == pytest.approx(2.897771955e-3 / 5778.0, rel=1e-4)  # Wien's displacement law


def test_planck_sun_total_at_1_au():
    lam = np.geomspace(1e-8, 1e-3, 200001)
    expected = SIGMA * 5778.0**4 * (R_SUN / AU) ** 2  # 1366.8 W/m^2
    got = np.trapezoid(rad.planck_solar_irradiance(lam), lam)
    assert got == pytest.approx(expected, rel=1e-5)
    assert got == pytest.approx(1366.8, abs=0.1)
    nominal = np.trapezoid(rad.planck_solar_irradiance(lam, temperature_k=5772.0), lam)
    assert nominal == pytest.approx(1361.0, abs=0.5)  # IAU 2015 nominal T_eff and total solar irradiance
    _, e_far = rad.solar_spectrum("planck_5778k", [5e-7])
    assert e_far[0] == pytest.approx(math.pi * rad.planck_spectral_radiance(5e-7, 5778.0)[()] * (R_SUN / AU) ** 2)


def test_shipped_spectrum_integral_and_source():
    text, tab = _table()
    assert "ASTM G173-03" in text and "pvlib" in text  # the header names the source
    assert tab[0, 0] == 280.0 and tab[-1, 0] == 4000.0 and len(tab) == 2002
    assert np.trapezoid(tab[:, 1], tab[:, 0]) == pytest.approx(1348.0, abs=0.2)  # NREL's G173 ETR total
    lam, e0 = rad.solar_spectrum()  # SI: m and W m^-2 m^-1
    assert np.trapezoid(e0, lam) == pytest.approx(np.trapezoid(tab[:, 1], tab[:, 0]), rel=1e-12)
    assert np.allclose(lam, tab[:, 0] * 1e-9) and np.allclose(e0, tab[:, 1] * 1e9)


def test_planck_sun_resembles_the_measured_sun():
    lam, e0 = rad.solar_spectrum()
    _, ep = rad.solar_spectrum("planck_5778k")
    m = (lam >= 4e-7) & (lam <= 1e-6)
    assert np.trapezoid(ep[m], lam[m]) == pytest.approx(np.trapezoid(e0[m], lam[m]), rel=0.05)


# ---------------------------------------------------------------- units
@given(st.floats(1e-6, 1e6))
def test_spectral_unit_round_trip(x):
    assert rad.spectral_per_um_to_per_m(rad.spectral_per_m_to_per_um(x)) == pytest.approx(x, rel=1e-12)
    # 1 W m^-2 sr^-1 um^-1 is 1e6 W m^-2 sr^-1 m^-1
    assert rad.spectral_per_um_to_per_m(x) == pytest.approx(x * 1e6, rel=1e-12)


def test_band_integral_same_in_per_um_and_per_m():
    lam, e0 = rad.solar_spectrum()
    per_m = np.trapezoid(e0, lam)
    per_um = np.trapezoid(rad.spectral_per_m_to_per_um(e0), lam * 1e6)
    assert per_um == pytest.approx(per_m, rel=1e-12)


@given(st.floats(2e-7, 5e-6), st.floats(1e-3, 1e3))
def test_photons_watts_round_trip(lam, watts):
    photons = rad.photon_radiance(lam, watts)
    assert float(photons) * H * C / lam == pytest.approx(watts, rel=1e-12)


# ---------------------------------------------------------------- sun to sensor
def test_lambertian_radiance_and_energy_conservation():
    assert float(rad.lambertian_radiance(1000.0, reflectance=0.2)) == pytest.approx(200.0 / math.pi)
    # a white Lambertian surface re-emits all the irradiance: integral of L cos(theta) over the hemisphere
    L = float(rad.lambertian_radiance(1000.0, reflectance=1.0))
    th = np.linspace(0, math.pi / 2, 20001)
    exitance = 2 * math.pi * np.trapezoid(L * np.cos(th) * np.sin(th), th)
    assert exitance == pytest.approx(1000.0, rel=1e-8)


def test_atmosphere_paths():
    assert rad.atmosphere_transmissions(0.23, "both") == (0.77, 0.77)
    assert rad.atmosphere_transmissions(0.23, "down") == (0.77, 1.0)
    assert rad.atmosphere_transmissions(0.23, "up") == (1.0, 0.77)
    e = rad.surface_irradiance(1000.0, sun_zenith_deg=60.0, transmission_down=0.77)
    assert float(e) == pytest.approx(1000 * 0.5 * 0.77)
    assert float(rad.toa_radiance(10.0, transmission_up=0.77, path_radiance=2.0)) == pytest.approx(9.7)


def test_paper_figure2_reading_surface_and_toa():
    """Albedo 0.2, 23 % absorption: the surface curve carries one pass, the TOA curve two."""
    clear = radiometry_of(atmosphere_absorption=0.0)
    both = radiometry_of()
    down = radiometry_of(atmosphere_path="down")
    up = radiometry_of(atmosphere_path="up")
    assert both.radiance_surface_band_w_per_m2_sr == pytest.approx(0.77 * clear.radiance_surface_band_w_per_m2_sr)
    assert both.radiance_toa_band_w_per_m2_sr == pytest.approx(0.77**2 * clear.radiance_toa_band_w_per_m2_sr)
    assert down.radiance_toa_band_w_per_m2_sr == pytest.approx(up.radiance_toa_band_w_per_m2_sr)
    assert up.radiance_surface_band_w_per_m2_sr == pytest.approx(clear.radiance_surface_band_w_per_m2_sr)
    # surface radiance by hand: rho E0 cos(sza) T / pi over 450-900 nm of the table
    _, tab = _table()
    m = (tab[:, 0] >= 450) & (tab[:, 0] <= 900)
    e_band = np.trapezoid(tab[m, 1], tab[m, 0])
    hand = 0.2 * e_band * math.cos(math.radians(30.0)) * 0.77 / math.pi
    assert both.radiance_surface_band_w_per_m2_sr == pytest.approx(hand, rel=1e-9)


def radiometry_of(**illumination):
    return rad.radiometric_budget(_system(illumination=illumination))


def test_camera_equation_hand_value():
    e = rad.focal_plane_irradiance(100.0, f_number=10.0, transmission=0.8, obscuration_ratio=0.5)
    assert float(e) == pytest.approx(math.pi * 100 * 0.8 * 0.75 / 400)  # 0.471239 W/m^2


@pytest.mark.parametrize("f_number", [1.0, 4.0, 9.72])
def test_camera_equation_is_radiance_over_the_cone(f_number):
    """E = integral of L cos(theta) over the cone of half-angle sin(theta) = 1 / (2 F#) (aplanatic)."""
    L = 50.0
    th_max = math.asin(1 / (2 * f_number))
    th = np.linspace(0, th_max, 20001)
    e_cone = 2 * math.pi * np.trapezoid(L * np.cos(th) * np.sin(th), th)
    assert float(rad.focal_plane_irradiance(L, f_number=f_number)) == pytest.approx(e_cone, rel=1e-8)


def test_electrons_hand_computation():
    # flat 2 W m^-2 um^-1 on the focal plane over 500-600 nm, 10 um pixel, 1 ms, QE 0.5
    lam = np.linspace(500e-9, 600e-9, 101)
    e_fp = np.full_like(lam, 2e6)
    n = rad.electrons_per_pixel(lam, e_fp, pixel_area_m2=1e-10, integration_time_s=1e-3, qe=0.5)
    hand = 1e-3 * 1e-10 * 0.5 * 2e6 * (600e-9**2 - 500e-9**2) / 2 / (H * C)  # integral of lambda dlambda
    assert n == pytest.approx(hand, rel=1e-12)


def test_signal_chain_by_hand_with_tdi_and_obscuration():
    s = _system(
        optics={"obscuration_ratio": 0.3, "transmission": 0.9},
        detector={"tdi_stages": 8, "qe": 0.6},
        radiometry={"integration_time_s": 1e-4},
        illumination={"sun_zenith_deg": 40.0},
    )
    _, tab = _table()
    lam_m = tab[:, 0] * 1e-9
    m = (tab[:, 0] >= 450) & (tab[:, 0] <= 900)  # band edges are table points
    photon_irr = np.trapezoid(tab[m, 1] * 1e9 * lam_m[m] / (H * C), lam_m[m])  # photons s^-1 m^-2 at TOA
    radiance_factor = 0.77 * math.cos(math.radians(40)) * 0.2 / math.pi * 0.77
    camera = math.pi * 0.9 * (1 - 0.09) / (4 * 10.0**2)
    hand = photon_irr * radiance_factor * camera * (10e-6) ** 2 * 1e-4 * 0.6 * 8
    assert rad.signal_electrons(s) == pytest.approx(hand, rel=1e-9)
    r = rad.radiometric_budget(s)
    assert r.signal_e == pytest.approx(hand, rel=1e-9)
    assert r.electrons_per_stage_e == pytest.approx(hand / 8, rel=1e-9)


def test_signal_is_linear_in_reflectance_plus_path_radiance():
    s = _system(illumination={"path_radiance_w_per_m2_sr_per_um": 5.0})
    n0, n1, n2 = rad.signal_electrons(s, [0.0, 0.1, 0.2])
    assert n0 > 0 and (n2 - n1) == pytest.approx(n1 - n0, rel=1e-12)
    no_path = rad.signal_electrons(_system(), 0.1)
    assert n1 - n0 == pytest.approx(no_path, rel=1e-12)


def test_tabulated_qe_interpolates():
    s = _system(detector={"qe": [0.2, 0.8], "qe_wavelengths_m": [4e-7, 1e-6]})
    assert s.detector.qe_at([4e-7, 7e-7, 1e-6, 2e-6]).tolist() == pytest.approx([0.2, 0.5, 0.8, 0.0])


def test_integration_time_defaults_to_line_time():
    s = _system()
    assert s.integration_time_s == pytest.approx(s.gsd_alt_m / s.orbit.ground_speed_m_per_s)
    assert s.gsd_alt_m == pytest.approx(10e-6 * 500e3 / 5.0)  # f = 10 * 0.5 m
    assert _system(radiometry={"integration_time_s": 2e-3}).integration_time_s == 2e-3


# ---------------------------------------------------------------- noise
def test_noise_terms_by_hand_and_in_quadrature():
    nb = rad.noise_budget(
        40000.0,
        stages=16,
        integration_time_s=1e-3,
        read_noise_e=20.0,
        dark_current_e_per_s=2500.0,
        readout="ccd",
        full_well_e=65536.0,
        bit_depth=12,
        prnu=0.01,
    )
    assert nb.shot_e == pytest.approx(200.0)
    assert nb.dark_e == pytest.approx(math.sqrt(2500 * 1e-3 * 16))  # sqrt(40)
    assert nb.read_e == pytest.approx(20.0)
    assert nb.quantisation_e == pytest.approx(16.0 / math.sqrt(12))  # 65536 e- / 4096 DN
    assert nb.prnu_e == pytest.approx(0.01 * 40000 / 4)
    terms = [nb.shot_e, nb.dark_e, nb.read_e, nb.quantisation_e, nb.prnu_e]
    assert nb.total_e == pytest.approx(math.sqrt(sum(t * t for t in terms)))
    assert nb.snr == pytest.approx(40000 / nb.total_e)


@given(st.integers(1, 256), st.floats(0.5, 100.0))
@settings(max_examples=40)
def test_read_noise_ccd_once_cmos_sqrt_stages(n, sigma):
    ccd = rad.noise_budget(1000.0, stages=n, read_noise_e=sigma, readout="ccd")
    cmos = rad.noise_budget(1000.0, stages=n, read_noise_e=sigma, readout="cmos")
    assert ccd.read_e == pytest.approx(sigma)
    assert cmos.read_e == pytest.approx(sigma * math.sqrt(n))


def test_shot_limited_snr_grows_as_sqrt_stages():
    one = rad.radiometric_budget(_system(detector={"tdi_stages": 1}))
    many = rad.radiometric_budget(_system(detector={"tdi_stages": 64}))
    assert many.snr / one.snr == pytest.approx(8.0, rel=1e-9)


def test_contrast_snr_closed_form_for_an_ideal_detector():
    s = _system()
    n1 = rad.signal_electrons(s, 1.0)
    expected = 0.08 * n1 / math.sqrt(0.15 * n1)  # (S15 - S7) / sqrt(S15)
    assert rad.contrast_snr(s) == pytest.approx(expected, rel=1e-9)
    assert rad.radiometric_budget(s).contrast_snr == pytest.approx(expected, rel=1e-9)


def test_full_well_saturation_flag():
    s = _system(detector={"tdi_stages": 32})
    n = rad.signal_electrons(s)
    ok = rad.radiometric_budget(_system(detector={"tdi_stages": 32, "full_well_e": 2 * n}))
    assert not ok.saturated and ok.well_fill == pytest.approx(0.5)
    sat = rad.radiometric_budget(_system(detector={"tdi_stages": 32, "full_well_e": 0.9 * n}))
    assert sat.saturated
    # digital (CMOS) TDI: each stage's charge must fit, not the sum
    cmos = rad.radiometric_budget(_system(detector={"tdi_stages": 32, "full_well_e": 0.9 * n, "readout": "cmos"}))
    assert not cmos.saturated and cmos.well_fill == pytest.approx(1 / (0.9 * 32))


def test_preset_budget_is_realistic_and_json_ready(ankarasat3):
    r = rad.radiometric_budget(ankarasat3)
    assert ankarasat3.detector.tdi_stages > 1 and r.noise.read_e > 0 and r.noise.quantisation_e > 0
    assert 20 < r.contrast_snr < 300 and not r.saturated
    d = json.loads(json.dumps(r.to_dict(include_spectra=True)))
    assert d["radiance_toa_band_w_per_m2_sr"] < d["radiance_surface_band_w_per_m2_sr"]
    assert len(d["spectra"]["wavelength_m"]) == len(d["spectra"]["radiance_toa_w_per_m2_sr_per_um"])
    # spectra in the JSON are per um: the peak of the TOA radiance is tens of W m^-2 sr^-1 um^-1
    assert 10 < max(d["spectra"]["radiance_toa_w_per_m2_sr_per_um"]) < 200


# ---------------------------------------------------------------- configuration
@pytest.mark.parametrize(
    "section, values, words",
    [
        ("detector", {"qe": 1.5}, ["detector.qe", "1.5", "(0, 1]"]),
        ("detector", {"qe": [0.5, 0.6]}, ["detector.qe_wavelengths_m"]),
        ("detector", {"qe": [0.5, 1.2], "qe_wavelengths_m": [4e-7, 9e-7]}, ["qe[1]", "1.2"]),
        ("detector", {"bit_depth": 12}, ["detector.bit_depth", "detector.full_well_e"]),
        ("detector", {"read_noise_e": -1.0}, ["detector.read_noise_e", "-1.0"]),
        ("detector", {"readout": "ccdd"}, ["detector.readout", "ccdd"]),
        ("illumination", {"sun_zenith_deg": 95.0}, ["illumination.sun_zenith_deg", "95.0"]),
        ("illumination", {"atmosphere_path": "sideways"}, ["illumination.atmosphere_path", "sideways"]),
        ("illumination", {"solar_spectrum": "vega"}, ["illumination.solar_spectrum", "vega"]),
        ("illumination", {"reflectance": 1.1}, ["illumination.reflectance", "1.1"]),
        ("radiometry", {"band_m": [9e-7, 4.5e-7]}, ["radiometry.band_m", "min < max"]),
        ("radiometry", {"integration_time_s": 0.0}, ["radiometry.integration_time_s"]),
        ("radiometry", {"exposure_s": 1.0}, ["radiometry.exposure_s", "unknown key"]),
    ],
)
def test_errors_name_the_key(section, values, words):
    with pytest.raises(ConfigError) as exc:
        _system(**{section: values})
    for w in words:
        assert w in str(exc.value)


def test_function_errors_name_the_parameter():
    with pytest.raises(ConfigError, match="illumination.sun_zenith_deg = 90"):
        rad.surface_irradiance(1.0, sun_zenith_deg=90)
    with pytest.raises(ConfigError, match="optics.obscuration_ratio = 1.0"):
        rad.focal_plane_irradiance(1.0, f_number=2, obscuration_ratio=1.0)
    with pytest.raises(ConfigError, match="detector.readout"):
        rad.noise_budget(1.0, readout="ccd2")
    with pytest.raises(ConfigError, match="needs detector.full_well_e"):
        rad.noise_budget(1.0, bit_depth=12)
    with pytest.raises(InputError, match="reflectance"):
        rad.signal_electrons(_system(), 1.5)


def test_old_files_stay_valid_and_round_trip():
    s = _system()  # no radiometric keys at all: defaults
    assert s.detector.qe == 1.0 and s.detector.read_noise_e == 0.0 and s.illumination.reflectance == 0.2
    assert ImagingSystem.from_dict(s.to_dict()) == s
    t = _system(detector={"qe": [0.3, 0.7, 0.4], "qe_wavelengths_m": [4e-7, 7e-7, 1e-6]})
    assert ImagingSystem.from_dict(t.to_dict()) == t
    assert s.replace({"illumination.sun_zenith_deg": 60.0}).illumination.sun_zenith_deg == 60.0


# ---------------------------------------------------------------- figure 2
def test_spectral_radiance_plot_is_written_atomically(tmp_path, ankarasat3):
    from satchain.report.radiometry_plot import plot_spectral_radiance

    out = tmp_path / "fig" / "spectral_radiance.png"
    plot_spectral_radiance(rad.radiometric_budget(ankarasat3), out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000
    assert sorted(p.name for p in out.parent.iterdir()) == ["spectral_radiance.png"]  # no temp files left
