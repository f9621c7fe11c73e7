"""Issue 32, point 2: the bands of a multiband focal plane -- spectral responses (closed forms), the ``[[bands]]`` keys
and ``ImagingSystem.for_band``, the budget per band (its own pixel, Nyquist, radiometry, registration offset from the
PAN band) and the ``ankarasat3-pms`` preset; bad input (point 8) in one line, exit 2."""

from __future__ import annotations

import copy
import json
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate, special
from typer.testing import CliRunner

import satchain
from satchain.cli.main import app
from satchain.config.response import (
    SUPPORT_FLOOR,
    SuperGaussianResponse,
    TabulatedResponse,
    response_quadrature,
)
from satchain.config.system import ImagingSystem, load_preset
from satchain.errors import ConfigError
from satchain.prediction.budget import budget, budget_results
from satchain.radiometry import radiometric_budget

# ----------------------------------------------------------------------------------------------- responses


def _fwhm_of_samples(lam: np.ndarray, r: np.ndarray) -> float:
    """FWHM of a single-peaked sampled curve, by linear interpolation of its half-maximum crossings."""
    half = r.max() / 2
    above = np.flatnonzero(r >= half)
    i0, i1 = above[0], above[-1]
    left = np.interp(half, [r[i0 - 1], r[i0]], [lam[i0 - 1], lam[i0]])
    right = np.interp(half, [r[i1 + 1], r[i1]], [lam[i1 + 1], lam[i1]])
    return float(right - left)


@settings(max_examples=40, deadline=None)
@given(
    center_nm=st.floats(400, 2000),
    fwhm_nm=st.floats(5, 300),
    order=st.integers(1, 8),
    n=st.integers(7, 15),
)
def test_a_super_gaussians_quadrature_integrates_to_its_area_with_its_centre_as_centroid(center_nm, fwhm_nm, order, n):
    r = SuperGaussianResponse(center_nm * 1e-9, fwhm_nm * 1e-9, order)
    lam, w = response_quadrature(r, n)
    # the area in closed form: fwhm Gamma(1 + 1/2n) / ln2^(1/2n); a Gaussian: fwhm sqrt(pi / (4 ln 2))
    p = 1 / (2 * order)
    area = fwhm_nm * 1e-9 * math.gamma(1 + p) / math.log(2) ** p
    if order == 1:
        assert area == pytest.approx(fwhm_nm * 1e-9 * math.sqrt(math.pi / (4 * math.log(2))), rel=1e-12)
    # truncated at 1e-3 of the peak: the tails beyond hold < 3e-4 of the area (Gaussian: erfc(3.717 / sqrt 2))
    assert w.sum() == pytest.approx(area, rel=4e-4)
    assert w.sum() < area
    assert np.sum(w * lam) / np.sum(w) == pytest.approx(center_nm * 1e-9, rel=1e-9)
    assert len(lam) == n and np.all(np.diff(lam) > 0) and np.all(w > 0)
    lo, hi = r.support_m
    assert lo < lam[0] and lam[-1] < hi


@pytest.mark.parametrize("order", [1, 2, 4, 10])
def test_the_sampled_curve_has_the_stated_fwhm_and_its_support_ends_at_the_floor(order):
    r = SuperGaussianResponse(6.6e-7, 6e-8, order)
    lam = np.linspace(5.5e-7, 7.7e-7, 200001)
    assert _fwhm_of_samples(lam, r(lam)) == pytest.approx(6e-8, rel=1e-5)
    lo, hi = r.support_m
    assert r(np.array([lo, hi])) == pytest.approx([SUPPORT_FLOOR, SUPPORT_FLOOR], rel=1e-9)
    assert 6.6e-7 - lo == pytest.approx(hi - 6.6e-7, rel=1e-12)
    # Gaussian: the floor is at sigma sqrt(2 ln 1000), sigma = fwhm / (2 sqrt(2 ln 2))
    if order == 1:
        assert hi - 6.6e-7 == pytest.approx(6e-8 / (2 * math.sqrt(2 * math.log(2))) * math.sqrt(2 * math.log(1000)))


def test_the_super_gaussian_area_matches_numerical_integration():
    for order in (1, 3, 6):
        r = SuperGaussianResponse(8e-7, 1.4e-7, order)
        quad_nm, _ = integrate.quad(lambda x, r=r: float(r(x * 1e-9)), -200.0, 1800.0, points=[800.0], limit=200)
        assert r.area_m == pytest.approx(quad_nm * 1e-9, rel=1e-7)


def test_a_tabulated_responses_quadrature_is_exact_for_a_flat_and_a_triangular_table():
    flat = TabulatedResponse((5e-7, 6e-7), (0.8, 0.8))
    lam, w = response_quadrature(flat, 7)
    assert w.sum() == pytest.approx(0.8 * 1e-7, rel=1e-12)
    assert np.sum(w * lam) / w.sum() == pytest.approx(5.5e-7, rel=1e-12)
    assert np.allclose(w, w[0]) and np.allclose(np.diff(lam), 1e-7 / 7)
    # a right triangle rising from 500 to 600 nm: area h b / 2, centroid two thirds of the way
    tri = TabulatedResponse((4e-7, 5e-7, 6e-7, 7e-7), (0.0, 0.0, 1.0, 0.0))
    assert tri.support_m == (5e-7, 7e-7)
    lam, w = response_quadrature(tri, 9)
    assert w.sum() == pytest.approx(1e-7, rel=1e-9)
    assert np.sum(w * lam) / w.sum() == pytest.approx(6e-7, rel=1e-9)  # a symmetric triangle 500-700 nm


# ----------------------------------------------------------------------------------------------- keys

SYSTEM: dict[str, Any] = {
    "name": "two-band",
    "orbit": {"altitude_m": 500000.0},
    "optics": {"aperture_diameter_m": 0.5, "f_number": 10.0, "wavelengths_m": [6e-7]},
    "detector": {"pitch_m": 5e-6, "qe": 0.8, "tdi_stages": 8},
}


def _system(*bands: dict[str, Any], **over: Any) -> ImagingSystem:
    d = copy.deepcopy(SYSTEM)
    d.update(over)
    d["bands"] = list(bands)
    return ImagingSystem.from_dict(d)


def _one_line_error(*bands: dict[str, Any]) -> str:
    with pytest.raises(ConfigError) as exc:
        _system(*bands)
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_bands_given_by_wavelengths_work_as_before():
    s = _system({"name": "a", "wavelengths_m": [5e-7, 6e-7], "wavelength_weights": [1, 3], "band_m": [4.5e-7, 6.5e-7]})
    b = s.for_band(0)  # just the replaced keys: wavelengths, weights and band, nothing else
    plain = load_preset("ankarasat3")
    assert b.optics.wavelengths_m == (5e-7, 6e-7) and b.optics.wavelength_weights == (1, 3)
    assert b.radiometry.band_m == (4.5e-7, 6.5e-7)
    assert b.detector == s.detector and b.motion == s.motion and b.bands == ()
    assert plain.for_band(0) is plain


def test_a_response_sets_the_optics_band_and_qe():
    s = _system({"name": "red", "response": {"center_m": 6.6e-7, "fwhm_m": 6e-8}, "qe": 0.5})
    b = s.for_band(0)
    lam = np.asarray(b.optics.wavelengths_m)
    w = np.asarray(b.optics.wavelength_weights)
    assert len(lam) == 11 and w.sum() == pytest.approx(1.0)
    assert np.sum(lam * w) == pytest.approx(6.6e-7, rel=1e-9)
    lo, hi = b.radiometry.band_m
    half = 3e-8 * math.sqrt(math.log(1000) / math.log(2))
    assert (lo, hi) == pytest.approx((6.6e-7 - half, 6.6e-7 + half), rel=1e-12)
    # QE x response: 0.5 at the centre, 0.25 at the half-maximum points, 0 outside the support
    assert b.detector.qe_at([6.6e-7, 6.9e-7, 6.3e-7]) == pytest.approx([0.5, 0.25, 0.25], rel=1e-3)
    assert b.detector.qe_at([hi * 1.01]) == pytest.approx([0.0])


def test_a_band_with_a_flat_table_collects_what_a_flat_band_does(tmp_path):
    """A table 1 inside 500-600 nm (edges 0.01 nm wide) and a band_m = 500-600 nm band with the same QE: the same
    signal (the radiometry integrates QE x response)."""
    csv = tmp_path / "flat.csv"
    csv.write_text("# a flat filter\nwavelength_m,response\n4.9999e-7,0\n5e-7,1\n6e-7,1\n6.0001e-7,0\n")
    d = copy.deepcopy(SYSTEM)
    d["bands"] = [{"name": "t", "response_file": "flat.csv"}, {"name": "f", "wavelengths_m": [5.5e-7],
                                                                "band_m": [5e-7, 6e-7]}]  # fmt: skip
    (tmp_path / "s.toml").write_text(_toml(d))
    s = ImagingSystem.from_toml(tmp_path / "s.toml")
    assert s.bands[0].response_values == (0.0, 1.0, 1.0, 0.0)
    table, flat = radiometric_budget(s.for_band(0)), radiometric_budget(s.for_band(1))
    assert table.signal_e == pytest.approx(flat.signal_e, rel=5e-4)


def _toml(d: dict[str, Any]) -> str:
    """A system dict as TOML: its tables, then each [[bands]] (inline tables inside)."""

    def value(v: Any) -> str:
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return json.dumps(v)

    lines = [f"{k} = {value(v)}" for k, v in d.items() if not isinstance(v, (dict, list))]
    for k, v in d.items():
        if isinstance(v, dict):
            lines += [f"[{k}]", *(f"{kk} = {value(x)}" for kk, x in v.items())]
    for band in d.get("bands", []):
        lines += ["[[bands]]", *(f"{kk} = {value(x)}" for kk, x in band.items())]
    return "\n".join(lines) + "\n"


def test_pitch_tdi_and_width_follow_the_band_on_the_same_telescope():
    ms_band = {"name": "ms", "wavelengths_m": [6e-7], "pitch_m": 2e-5, "active_width_m": 1.6e-5, "tdi_stages": 2}
    s = _system({"name": "pan", "wavelengths_m": [6e-7]}, ms_band)
    pan, ms = s.for_band(0), s.for_band(1)
    assert ms.focal_length_m == pan.focal_length_m == s.focal_length_m == 5.0
    assert ms.detector.pitch_x_m == ms.detector.pitch_y_m == 2e-5
    assert ms.detector.active_width_x_m == ms.detector.active_width_y_m == 1.6e-5
    assert ms.detector.tdi_stages == 2 and pan.detector.tdi_stages == 8
    assert ms.gsd_alt_m == pytest.approx(500000.0 * 2e-5 / 5.0) and ms.gsd_act_m == pytest.approx(2.0)
    # signal per stage: the active area (16x) over the line time (4x, at its own GSD); 2 stages against 8
    ratio = radiometric_budget(ms).signal_e / radiometric_budget(pan).signal_e
    assert ratio == pytest.approx((1.6e-5 / 5e-6) ** 2 * 4 * 2 / 8, rel=1e-9)


def test_line_of_sight_angles_are_in_the_bands_own_pixels():
    osc = [{"axis": "act", "amplitude_px": 1.0, "frequency_hz": 20.0}]
    s = _system({"name": "pan", "wavelengths_m": [6e-7]}, {"name": "ms", "wavelengths_m": [6e-7], "pitch_m": 2e-5},
                motion={"oscillation": osc, "jitter_rms_px": 0.2, "smear_px": 0.5})  # fmt: skip
    ms = s.for_band(1)
    assert ms.motion.oscillation[0].amplitude_px == pytest.approx(0.25)
    assert ms.motion.jitter_rms_px == pytest.approx(0.05)
    assert ms.motion.smear_px == 0.5  # motion over one integration time: the line time scales with the pitch
    assert s.for_band(0).motion == s.motion


def test_band_names_and_index():
    s = load_preset("ankarasat3-pms")
    assert s.band_names == ("pan", "blue", "green", "red", "nir")
    assert s.band_index("NIR") == 4 and s.band_index("pan") == 0
    with pytest.raises(ConfigError, match=r"band = 'swir': not a band of 'ankarasat3-pms'; its bands are 'pan', "):
        s.band_index("swir")
    with pytest.raises(ConfigError, match=r"band index = 5: the system has 5 bands \(0 to 4: pan, blue"):
        s.for_band(5)
    assert _system({"wavelengths_m": [6e-7]}, {"wavelengths_m": [7e-7]}).band_names == ("band1", "band2")
    with pytest.raises(ConfigError, match="no \\[\\[bands\\]\\]"):
        load_preset("ankarasat3").band_index("pan")


@pytest.mark.parametrize(
    ("bands", "message"),
    [
        ([{"name": "red", "wavelengths_m": [6e-7]}, {"name": "Red", "wavelengths_m": [6.5e-7]}],
         "bands[1].name = 'Red': the same as bands[0].name = 'red'; every band needs its own name"),
        ([{"name": "r", "wavelengths_m": [6e-7], "response": {"center_m": 6e-7, "fwhm_m": 5e-8}}],
         "bands[0]: give one of wavelengths_m, response or response_file (a table); got wavelengths_m and response"),
        ([{"name": "r"}], "give one of wavelengths_m, response or response_file (a table); got none"),
        ([{"name": "r", "response": {"center_m": 6e-7, "fwhm_m": 5e-8}, "band_m": [5e-7, 7e-7]}],
         "bands[0].band_m = [5e-07, 7e-07]: a band with a response takes its weights and band from the response"),
        ([{"name": "r", "response": {"center_m": 3e-7, "fwhm_m": 1e-7}}],
         "the response spans 1.422e-07-4.578e-07 m (to 1e-3 of its peak); it must lie within 2.8e-07-4e-06 m"),
        ([{"name": "r", "response_wavelengths_m": [5e-7, 6e-7, 5.5e-7], "response_values": [0, 1, 0]}],
         "bands[0].response_wavelengths_m[2] = 5.5e-07: not greater than the one before (6e-07)"),
        ([{"name": "r", "wavelengths_m": [6e-7], "qe": 1.5}], "bands[0].qe = 1.5: must be in (0, 1]"),
        ([{"name": "r", "wavelengths_m": [6e-7], "pitch_m": 1e-5, "active_width_m": 2e-5}],
         "bands[0].active_width_m = 2e-05: must be <= pitch_m (1e-05)"),
        ([{"name": "r", "wavelengths_m": [6e-7], "active_width_m": 6e-6}],
         "bands[0].active_width_m = 6e-06: must be <= the band's pitch (5e-06)"),
        ([{"name": "r", "wavelengths_m": [6e-7], "registration_offset_px": [0.3]}],
         "bands[0].registration_offset_px[1]"),
    ],
)  # fmt: skip
def test_bad_bands_are_refused_in_one_line_naming_the_key(bands, message):
    assert message in _one_line_error(*bands)


def test_a_table_that_is_not_increasing_is_refused_naming_the_file_and_line(tmp_path):
    csv = tmp_path / "blue.csv"
    csv.write_text("wavelength_m,response\n4.4e-7,0\n4.6e-7,1\n4.5e-7,1\n5.3e-7,0\n")
    d = copy.deepcopy(SYSTEM)
    d["bands"] = [{"name": "blue", "response_file": "blue.csv"}]
    (tmp_path / "s.toml").write_text(_toml(d))
    r = CliRunner().invoke(app, ["budget", "--system", str(tmp_path / "s.toml")])
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert r.exit_code == 2 and len(lines) == 1, r.output
    assert f"bands[0].response_file = '{csv}': line 4: wavelength_m 4.5e-07 is not greater than the row before " in (
        " ".join(r.output.split())
    )


def test_overlapping_band_names_exit_2_on_the_cli(tmp_path):
    d = copy.deepcopy(SYSTEM)
    d["bands"] = [{"name": "pan", "wavelengths_m": [6e-7]}, {"name": "PAN", "wavelengths_m": [6e-7]}]
    (tmp_path / "s.toml").write_text(_toml(d))
    r = CliRunner().invoke(app, ["budget", "--system", str(tmp_path / "s.toml"), "--json"])
    assert r.exit_code == 2 and "bands[1].name = 'PAN': the same as bands[0].name = 'pan'" in " ".join(r.output.split())


def test_a_system_with_bands_round_trips_through_its_dict_and_toml(tmp_path):
    s = load_preset("ankarasat3-pms")
    assert ImagingSystem.from_dict(s.to_dict()) == s
    (tmp_path / "s.toml").write_text(_toml(s.to_dict()))
    assert ImagingSystem.from_toml(tmp_path / "s.toml") == s


# ----------------------------------------------------------------------------------------------- budget


def test_a_system_without_bands_budgets_as_today():
    b = budget(load_preset("ankarasat3"))
    assert b.bands == () and "bands" not in b.to_dict()


def test_the_pan_band_of_the_pms_preset_is_the_reference_camera():
    ref, pms = budget(load_preset("ankarasat3")), budget(load_preset("ankarasat3-pms"))
    pan = pms.bands[0]
    assert pan.name == "pan" and pan.gsd_m == pytest.approx(ref.gsd_m, rel=1e-12)
    assert pan.mtf_at_nyquist_act == pytest.approx(ref.mtf_at_nyquist_act, rel=1e-12)
    assert pan.mtf_at_nyquist_alt == pytest.approx(ref.mtf_at_nyquist_alt, rel=1e-12)
    assert pan.snr == pytest.approx(ref.signal_snr, rel=1e-12) and pan.niirs == pytest.approx(ref.niirs, rel=1e-12)
    assert [b.niirs is None for b in pms.bands] == [False, True, True, True, True]
    # the system's own budget is unchanged by its bands
    assert (pms.mtf_at_nyquist_alt, pms.niirs, pms.snr) == (ref.mtf_at_nyquist_alt, ref.niirs, ref.snr)


def test_the_ms_bands_sample_at_four_times_the_pitch():
    s = load_preset("ankarasat3-pms")
    f = s.focal_length_m
    for b in budget(s).bands[1:]:
        assert b.gsd_m == pytest.approx(567000.0 * 4 * 5.88e-6 / f, rel=1e-12) and round(b.gsd_m, 2) == 1.96
        assert b.nyquist_alt_cy_per_mm == pytest.approx(1 / (2 * 4 * 5.88e-3), rel=1e-12)
    stated = {"blue": (450, 520), "green": (520, 600), "red": (630, 690), "nir": (760, 900)}
    for band in s.bands[1:]:
        r = band.response
        assert r is not None
        lo, hi = stated[band.name]
        assert (r.center_m - r.fwhm_m / 2, r.center_m + r.fwhm_m / 2) == pytest.approx((lo * 1e-9, hi * 1e-9))


def _circular_mtf(nu_lambda_f: np.ndarray) -> np.ndarray:
    x = np.clip(nu_lambda_f, 0, 1)
    return 2 / np.pi * (np.arccos(x) - x * np.sqrt(1 - x**2))


@pytest.mark.parametrize("order", [1, 4])
def test_a_bands_mtf_at_its_nyquist_is_diffraction_over_its_response_times_its_pixel(order):
    """Unobscured circular pupil, square pixel, no motion: MTF(Nyquist) = sinc(1/2) x the response-weighted mean
    of the diffraction MTF, integrated here with scipy's adaptive quadrature."""
    resp = {"center_m": 8.3e-7, "fwhm_m": 1.4e-7, "order": order}
    s = _system({"name": "nir", "response": resp, "pitch_m": 8e-6})
    b = budget(s).bands[0]
    ny_cy_per_m = 1 / (2 * 8e-6)
    r = SuperGaussianResponse(8.3e-7, 1.4e-7, order)
    lo, hi = r.support_m
    num, _ = integrate.quad(lambda nm: float(r(nm * 1e-9)) * float(_circular_mtf(np.array(ny_cy_per_m * nm * 1e-8))),
                            lo * 1e9, hi * 1e9, limit=200)  # fmt: skip
    den, _ = integrate.quad(lambda nm: float(r(nm * 1e-9)), lo * 1e9, hi * 1e9, limit=200)
    expected = num / den * np.sinc(0.5)
    assert b.mtf_at_nyquist_act == pytest.approx(expected, abs=2e-4)
    assert b.mtf_at_nyquist_alt == pytest.approx(expected, abs=2e-4)
    assert b.center_wavelength_m == pytest.approx(8.3e-7, rel=1e-9)


def test_the_registration_delay_and_static_offset():
    s = load_preset("ankarasat3-pms")
    d = s.to_dict()
    d["bands"][0]["registration_offset_px"] = [0.4, -0.8]  # PAN px: 0.1 / -0.2 MS px
    d["bands"][3]["registration_offset_px"] = [0.30, 0.05]
    s = ImagingSystem.from_dict(d)
    bands = {b["name"]: b for b in budget_results(s)["bands"]}
    # the image crosses the focal plane at ground speed x f / range
    v = s.orbit.ground_speed_m_per_s * s.focal_length_m / 567000.0
    assert bands["red"]["registration"]["delay_s"] == pytest.approx(9.0e-3 / v, rel=1e-9)
    assert bands["red"]["registration"]["delay_lines"] == pytest.approx(9.0e-3 / 23.52e-6, rel=1e-12)
    assert bands["red"]["registration"]["static_px"] == pytest.approx({"alt": 0.30 - 0.1, "act": 0.05 + 0.2})
    assert bands["red"]["registration"]["static_m"]["alt"] == pytest.approx(0.2 * 1.96, rel=1e-9)
    assert bands["pan"]["registration"]["static_px"] == pytest.approx({"alt": 0.0, "act": 0.0})
    assert bands["green"]["registration"]["static_reference_px"] == pytest.approx({"alt": -0.4, "act": 0.8})


@pytest.mark.parametrize(("f_hz", "phase_deg"), [(20.0, 0.0), (350.0, 40.0)])
def test_an_oscillation_misregisters_the_bands_as_the_window_means_at_the_two_times(f_hz, phase_deg):
    """A row's displacement is the oscillation's mean over its TDI window; the band sees the ground point
    delay_s after the PAN: the offset, row by row, against a direct numerical average (band px)."""
    osc = [{"axis": "act", "amplitude_px": 1.0, "frequency_hz": f_hz, "phase_deg": phase_deg}]
    s = load_preset("ankarasat3-pms").replace({"motion.oscillation": osc})
    bands = budget_results(s)["bands"]
    pan, ms = s.for_band(0), s.for_band(4)
    t_p, t_b = 16 * pan.line_time_s, 1 * ms.line_time_s
    for b in bands[1:]:
        reg = b["registration"]
        (o,) = reg["oscillations"]
        dt = reg["delay_s"]
        for t_c in np.linspace(0.0, 0.05, 7):  # the PAN row's window centre

            def mean(lo: float, width: float) -> float:
                t = np.linspace(lo, lo + width, 4001)
                return float(np.mean(np.sin(2 * np.pi * f_hz * t + np.radians(phase_deg))))

            # content moves against the line of sight: the band's content offset is minus the LOS difference
            numeric = -(mean(t_c + dt - t_b / 2, t_b) - mean(t_c - t_p / 2, t_p)) / 4  # PAN px -> MS px
            predicted = o["amplitude_px"] * math.sin(2 * math.pi * f_hz * t_c + math.radians(o["phase_deg"]))
            assert predicted == pytest.approx(numeric, abs=2e-4)
        if f_hz == 20.0:  # windows short against the period: 2 A |sin(pi f dt)|, PAN px -> MS px
            assert o["amplitude_px"] == pytest.approx(2 * abs(math.sin(math.pi * 20.0 * dt)) / 4, rel=2e-3)


def test_the_cli_prints_a_band_table_and_json_bands():
    r = CliRunner().invoke(app, ["budget", "--preset", "ankarasat3-pms"])
    assert r.exit_code == 0, r.output
    assert "bands:" in r.output and all(n in r.output for n in ("blue", "green", "red", "nir"))
    r = CliRunner().invoke(app, ["budget", "--preset", "ankarasat3-pms", "--json"])
    d = json.loads(r.stdout)
    assert [b["name"] for b in d["bands"]] == ["pan", "blue", "green", "red", "nir"]
    assert d["bands"] == json.loads(json.dumps(satchain.budget(load_preset("ankarasat3-pms")).to_dict()["bands"]))
    r = CliRunner().invoke(app, ["budget", "--preset", "ankarasat3", "--json"])
    assert "bands" not in json.loads(r.stdout)


def test_gaussian_response_in_closed_form_is_erf_between_the_half_maxima():
    """76.1 % of a Gaussian's area lies between its half-maximum points: erf(sqrt(ln 2))."""
    r = SuperGaussianResponse(5e-7, 1e-7)
    lam = np.linspace(4.5e-7, 5.5e-7, 100001)
    assert np.trapezoid(r(lam), lam) / r.area_m == pytest.approx(special.erf(math.sqrt(math.log(2))), rel=1e-8)


@pytest.mark.parametrize(("pass_direction", "latitude_deg"), [("descending", 40.0), ("ascending", -10.0)])
def test_the_earths_rotation_over_the_delay_misregisters_the_bands_as_its_ground_velocity_says(
    pass_direction, latitude_deg
):
    """No yaw steering: over the delay the ground moves at the Earth's surface velocity; its across-track part moves
    the band's image across track (x m = v_act t), its along-track part changes the delay itself (the image crosses
    the focal-plane offset at v_g - v_along instead of v_g)."""
    from satchain.config.sections import EARTH_RADIUS_M, EARTH_ROTATION_RAD_PER_S
    from satchain.config.sections_motion import cos_heading

    over = {"orbit.earth_rotation": True, "orbit.latitude_deg": latitude_deg, "orbit.inclination_deg": 97.7,
            "orbit.pass_direction": pass_direction}  # fmt: skip
    s = load_preset("ankarasat3-pms").replace(over)
    v_e = EARTH_ROTATION_RAD_PER_S * EARTH_RADIUS_M * math.cos(math.radians(latitude_deg))
    east, north = cos_heading(s.orbit)
    v_along, v_act = v_e * east, -v_e * north  # on the track's (y, x) axes, x to the left of the track
    v_g = s.orbit.ground_speed_m_per_s
    for b in budget_results(s)["bands"][1:]:
        reg = b["registration"]
        ground_m = reg["offset_alt_mm"] * 1e-3 * 567000.0 / s.focal_length_m
        t_nominal, t_actual = ground_m / v_g, ground_m / (v_g - v_along)
        assert reg["delay_s"] == pytest.approx(t_nominal, rel=1e-9)
        e = reg["earth_rotation"]
        assert e["delay_s"] == pytest.approx(t_actual, rel=1e-9)
        assert e["act_px"] == pytest.approx(v_act * t_actual / b["gsd_act_m"], rel=1e-9)
        assert e["alt_px"] == pytest.approx((t_actual - t_nominal) / s.for_band(b["index"]).line_time_s, rel=1e-9)
        assert abs(e["act_px"]) > 5  # tens of metres: what the ground processing must take out
    assert budget_results(load_preset("ankarasat3-pms"))["bands"][1]["registration"]["earth_rotation"] is None


@pytest.mark.parametrize("error", [2e-3, -5e-3])
def test_a_line_rate_error_misregisters_the_bands_by_the_lines_it_gains(error):
    """motion.line_rate_error e: the ground advances (1 + e) lines a line time, so it crosses a band's L lines of
    focal-plane offset in L / (1 + e) line times; registered by the nominal L, the band's content lies L (1 / (1 +
    e) - 1) of its lines away (ALT only; 0.2 MS px for blue at e = 1e-3). Alone it is the whole offset; with the
    Earth's rotation the two add to the offset of the whole drift (alt_scale a + e), exactly."""
    s = load_preset("ankarasat3-pms").replace({"motion.line_rate_error": error})
    for b in budget_results(s)["bands"][1:]:
        reg = b["registration"]
        band = s.for_band(b["index"])
        lines = reg["offset_alt_mm"] * 1e-3 / band.detector.pitch_y_m  # the band's own lines
        r = reg["line_rate"]
        assert r["alt_px"] == pytest.approx(lines * (1.0 / (1.0 + error) - 1.0), rel=1e-9)
        assert r["act_px"] == 0.0 and r["line_rate_error"] == error
        assert r["delay_s"] == pytest.approx(lines / (1.0 + error) * band.line_time_s, rel=1e-9)
        assert abs(r["alt_px"]) > 0.4  # blue's 255 lines and more
    earth = {"orbit.earth_rotation": True, "orbit.latitude_deg": 40.0, "orbit.inclination_deg": 97.7}
    both = s.replace(earth)
    alone = budget_results(load_preset("ankarasat3-pms").replace(earth))["bands"]
    for b, e in zip(budget_results(both)["bands"][1:], alone[1:], strict=True):
        reg, band = b["registration"], both.for_band(b["index"])
        lines = reg["offset_alt_mm"] * 1e-3 / band.detector.pitch_y_m
        a = lines * band.line_time_s / e["registration"]["earth_rotation"]["delay_s"]  # the Earth's alt_scale
        assert reg["earth_rotation"] == e["registration"]["earth_rotation"]  # the Earth's part: unchanged
        total = reg["earth_rotation"]["alt_px"] + reg["line_rate"]["alt_px"]
        assert total == pytest.approx(lines * (1.0 / (a + error) - 1.0), rel=1e-9)
    assert budget_results(load_preset("ankarasat3-pms"))["bands"][1]["registration"]["line_rate"] is None


@settings(max_examples=40, deadline=None)
@given(
    values=st.lists(st.floats(0.0, 1.0), min_size=3, max_size=12).filter(lambda v: max(v[1:-1], default=0) > 0.05),
    n=st.integers(5, 15),
)
def test_a_tables_quadrature_keeps_its_area_and_centroid_exactly(values, n):
    """A table is linear between its points: area and first moment in closed form, segment by segment."""
    lam = np.linspace(5e-7, 7e-7, len(values))
    r = TabulatedResponse(tuple(lam), tuple(values))
    nodes, w = response_quadrature(r, n)
    y = np.asarray(values)
    h = np.diff(lam)
    area = np.sum(h * (y[:-1] + y[1:]) / 2)
    # the first moment of a linear segment from (a, ya) to (b, yb): h (ya (2a + b) + yb (a + 2b)) / 6
    moment = np.sum(h * (y[:-1] * (2 * lam[:-1] + lam[1:]) + y[1:] * (lam[:-1] + 2 * lam[1:])) / 6)
    assert w.sum() == pytest.approx(area, rel=1e-9)
    assert np.sum(w * nodes) == pytest.approx(moment, rel=1e-9)


def test_a_bands_qe_curve_multiplies_its_response():
    band = {"name": "g", "response": {"center_m": 5.6e-7, "fwhm_m": 8e-8, "order": 4},
            "qe": [0.2, 0.8], "qe_wavelengths_m": [5e-7, 6.2e-7]}  # fmt: skip
    b = _system(band).for_band(np.int64(0))
    r = SuperGaussianResponse(5.6e-7, 8e-8, 4)
    for lam in (5.2e-7, 5.6e-7, 5.95e-7):
        qe = 0.2 + 0.6 * (lam - 5e-7) / 1.2e-7
        assert float(b.detector.qe_at(lam)) == pytest.approx(qe * float(r(lam)), rel=2e-3)
