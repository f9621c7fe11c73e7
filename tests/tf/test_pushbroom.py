"""Pushbroom TDI motion averaged over the TDI window (satchain.tf.pushbroom): closed forms, and references
integrated here over time with scipy.integrate.quad, independently of the Bessel series the module sums."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, special

from satchain import load_preset
from satchain.config.sections import EARTH_RADIUS_M, EARTH_ROTATION_RAD_PER_S
from satchain.tf.budget import SystemOTF, mtf_at_nyquist
from satchain.tf.pushbroom import (
    PushbroomTerms,
    jitter_psd_otf,
    oscillation_displacement_px,
    oscillation_otf,
    psd_window,
)

BASE = load_preset("ankarasat3")
T = BASE.detector.tdi_stages * BASE.line_time_s  # the TDI window, 16 line times


def _osc(**kw):
    return BASE.replace({"motion.oscillation": [dict(axis="act", phase_deg=30.0) | kw]})


def _window_average(nu, amp, c, phi, *, registered=True):
    """(1/T) int_0^T exp(-2 pi i nu (x(t) - d)) dt by quad, x = A sin(2 pi c t/T + phi), T = 1, d its mean."""
    d = amp * (math.cos(phi) - math.cos(2 * math.pi * c + phi)) / (2 * math.pi * c) if registered else 0.0

    def arg(t):
        return -2 * math.pi * nu * (amp * math.sin(2 * math.pi * c * t + phi) - d)

    re = integrate.quad(lambda t: math.cos(arg(t)), 0, 1, limit=400)[0]
    im = integrate.quad(lambda t: math.sin(arg(t)), 0, 1, limit=400)[0]
    return complex(re, im)


def _phase_average(nu, amp, c, n=48):
    """The expectation over the phase (trapezoid over a period: spectrally exact for a smooth periodic function)."""
    return np.mean([_window_average(nu, amp, c, 2 * math.pi * k / n) for k in range(n)])


# ------------------------------------------------------------------ oscillation
def test_whole_cycles_give_j0_at_nyquist():
    s = _osc(amplitude_px=0.5, frequency_hz=5.0 / T)
    ratio = mtf_at_nyquist(s)["act"] / mtf_at_nyquist(BASE)["act"]
    assert ratio == pytest.approx(special.j0(math.pi / 2), abs=0.003)
    assert mtf_at_nyquist(s)["alt"] == pytest.approx(mtf_at_nyquist(BASE)["alt"], abs=1e-12)  # ACT only
    g = PushbroomTerms(s).geometry()
    assert g["oscillations"][0]["line_displacement_amplitude_px"] < 1e-12  # whole cycles: no row moves


@pytest.mark.parametrize("amp, c, nu", [(0.8, 0.37, 0.5), (1.5, 2.5, 0.3), (0.5, 5.0, 0.5), (2.0, 0.02, 0.5)])
def test_phase_averaged_series_matches_time_integral(amp, c, nu):
    ref = _phase_average(nu, amp, c)
    got = float(oscillation_otf(nu, amplitude_px=amp, cycles_per_window=c))
    assert abs(ref.imag) < 1e-9  # the registered phase average is real
    assert got == pytest.approx(ref.real, abs=2e-6)


@pytest.mark.parametrize("amp, c, psi", [(0.8, 0.37, 0.4), (1.5, 2.5, 2.0), (3.0, 1.3, -1.0)])
def test_one_row_otf_matches_time_integral(amp, c, psi):
    phi = psi - math.pi * c  # the phase at t = 0 of the row whose mid-window phase is psi
    got = complex(oscillation_otf(0.4, amplitude_px=amp, cycles_per_window=c, phase_mid_rad=psi))
    assert got == pytest.approx(_window_average(0.4, amp, c, phi), abs=2e-6)


def test_slow_oscillation_only_displaces():
    # 2 px at 20 Hz: 0.02 cycles per window; the blur about the row mean is tiny, the rows move ~2 px
    c = 20.0 * T
    assert float(oscillation_otf(0.5, amplitude_px=2.0, cycles_per_window=c)) > 0.98
    g = oscillation_displacement_px(2.0, c, cycles_per_line=20.0 * BASE.line_time_s)
    assert g["amplitude_px"] == pytest.approx(2.0 * np.sinc(c), rel=1e-12)
    assert g["amplitude_px"] > 1.99


# ------------------------------------------------------------------ jitter PSD
def test_flat_high_frequency_psd_is_gaussian_jitter():
    sigma2 = 0.16
    s = BASE.replace({"motion.jitter_psd": {"axis": "act", "frequency_hz": [5e3, 5e4],
                                            "psd_px2_per_hz": [sigma2 / 45e3] * 2}})  # fmt: skip
    ratio = mtf_at_nyquist(s)["act"] / mtf_at_nyquist(BASE)["act"]
    assert ratio == pytest.approx(math.exp(-2 * math.pi**2 * sigma2 / 4), abs=0.006)
    g = PushbroomTerms(s).geometry()["jitter_psd"]["act"]
    assert g["sigma_px"] == pytest.approx(0.4, rel=1e-9)


def test_psd_expectation_matches_independent_integral():
    # a PSD around 1/T: partly blur, partly row displacement; the reference integrates v(s) and the s-average by quad
    Tw, dt = 1e-3, 1e-3 / 16
    f, p = [200.0, 1500.0, 4000.0], [2e-4, 1e-4, 0.0]
    w = psd_window(f, p, window_s=Tw, line_time_s=dt)

    def S(x):
        return float(np.interp(x, f, p))

    def v(s):
        def k(x):
            sc = np.sinc(x * Tw)
            return S(x) * (1 + sc * sc - 2 * sc * math.cos(2 * math.pi * x * s))

        return integrate.quad(k, f[0], f[-1], points=f[1:-1], limit=400)[0]

    for nu in (0.3, 0.5, 1.0):
        ref = integrate.quad(lambda s, nu=nu: math.exp(-2 * math.pi**2 * nu**2 * v(s)), 0, Tw / 2, limit=100)[0]
        ref /= Tw / 2
        assert float(jitter_psd_otf(nu, w)) == pytest.approx(ref, abs=1e-6)
    disp = integrate.quad(lambda x: S(x) * np.sinc(x * Tw) ** 2, f[0], f[-1], points=f[1:-1], limit=400)[0]
    assert w.displacement_variance_px2 == pytest.approx(disp, rel=1e-6)
    assert w.blur_variance_px2 + w.displacement_variance_px2 == pytest.approx(w.variance_px2, rel=1e-12)


def test_psd_tables_on_one_axis_add():
    one = {"axis": "alt", "frequency_hz": [1e3, 2e4], "psd_px2_per_hz": [1e-6, 1e-6]}
    s1 = BASE.replace({"motion.jitter_psd": [one, one]})
    s2 = BASE.replace({"motion.jitter_psd": {**one, "psd_px2_per_hz": [2e-6, 2e-6]}})
    f = np.array([0.0, 40.0, 85.0])
    for d in ("alt", "act"):
        a = SystemOTF(s1).components(*((0 * f, f) if d == "alt" else (f, 0 * f)))
        b = SystemOTF(s2).components(*((0 * f, f) if d == "alt" else (f, 0 * f)))
        np.testing.assert_allclose(a["jitter_psd_alt"], b["jitter_psd_alt"], atol=1e-12)


# ------------------------------------------------------------------ line-rate error, Earth rotation
def test_line_rate_error_is_sinc_along_track():
    s = BASE.replace({"motion.line_rate_error": 0.05})
    ratio = mtf_at_nyquist(s)["alt"] / mtf_at_nyquist(BASE)["alt"]
    assert ratio == pytest.approx(np.sinc(0.4), abs=0.003)
    assert mtf_at_nyquist(s)["act"] == pytest.approx(mtf_at_nyquist(BASE)["act"], abs=1e-12)


def _earth(**kw):
    keys = {"orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True}
    return PushbroomTerms(BASE.replace(keys | kw)).geometry()


def test_earth_rotation_at_the_equator():
    v_e = EARTH_ROTATION_RAD_PER_S * EARTH_RADIUS_M
    v_g = BASE.orbit.ground_speed_m_per_s
    i = math.radians(97.6)
    down, up = _earth(), _earth(**{"orbit.pass_direction": "ascending"})
    # descending: the ground under each next row lies tan(a) = v_e sin(i) / v_g px to -x (x points left of the track)
    assert down["shear_act_px_per_line"] == pytest.approx(-v_e * math.sin(i) / v_g, rel=1e-9)
    assert up["shear_act_px_per_line"] == pytest.approx(v_e * math.sin(i) / v_g, rel=1e-9)
    # retrograde track: its along-track direction points west, against the Earth: more ground per row
    for g in (down, up):
        assert g["alt_scale"] == pytest.approx(1 - v_e * math.cos(i) / v_g, rel=1e-12)
        assert g["tdi_drift_px"]["alt"] == pytest.approx(16 * (g["alt_scale"] - 1), rel=1e-12)
    assert down["tdi_drift_px"]["act"] == pytest.approx(16 * down["shear_act_px_per_line"], rel=1e-12)
    # a 5 deg near-vertical ground edge X = tan(5) Y appears at atan((1 + eps) tan 5 - sigma) in the image
    eps, sig = down["alt_scale"] - 1, down["shear_act_px_per_line"]
    assert math.degrees(math.atan((1 + eps) * math.tan(math.radians(5)) - sig)) == pytest.approx(8.8, abs=0.1)
    yaw = _earth(**{"orbit.yaw_steering": True})
    assert yaw["shear_act_px_per_line"] == 0.0 and yaw["tdi_drift_px"]["act"] == 0.0
    assert yaw["rotation_deg"] == pytest.approx(math.degrees(math.atan2(sig, 1 + eps)), rel=1e-9)
    assert yaw["alt_scale"] == pytest.approx(math.hypot(sig, 1 + eps), rel=1e-12)


def test_earth_rotation_across_track_speed_falls_with_latitude():
    v_e = EARTH_ROTATION_RAD_PER_S * EARTH_RADIUS_M
    i = math.radians(97.6)
    g = _earth(**{"orbit.latitude_deg": 60.0})["earth_rotation"]
    assert g["earth_velocity_along_track_m_per_s"] == pytest.approx(v_e * math.cos(i), rel=1e-9)
    expect = v_e * math.sqrt(math.cos(math.radians(60)) ** 2 - math.cos(i) ** 2)
    assert g["earth_velocity_act_m_per_s"] == pytest.approx(expect, rel=1e-9)


def test_components_on_a_grid_equal_the_cut():
    s = _osc(amplitude_px=0.7, frequency_hz=3000.0).replace({"motion.line_rate_error": -0.03})
    otf = SystemOTF(s)
    f = np.linspace(0, 170, 9)
    fx, fy = np.meshgrid(f, f)
    grid = otf.components(fx, fy)
    cut = otf.components(f, 0 * f)
    np.testing.assert_allclose(grid["oscillation_1"][0], cut["oscillation_1"], atol=1e-14)
    assert set(otf.component_names) >= {"oscillation_1", "tdi_drift"}


def test_without_the_keys_nothing_changes():
    otf = SystemOTF(BASE)
    assert otf.pushbroom is None and "tdi_drift" not in otf.component_names
    assert BASE.to_dict() == load_preset("ankarasat3").to_dict()
    assert "line_rate_error" not in BASE.to_dict()["motion"] and "earth_rotation" not in BASE.to_dict()["orbit"]
