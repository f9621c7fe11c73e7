"""Edge response, RER, overshoot, noise gain and GIQE 3/4/5 against closed forms and published values."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import erf

from satchain import ConfigError, InputError
from satchain.prediction import quality as q


def _gauss_mtf(f, sigma_px):
    """MTF of a Gaussian LSF of standard deviation sigma (pixels): exp(-2 pi^2 sigma^2 f^2)."""
    return np.exp(-2.0 * (np.pi * sigma_px * f) ** 2)


def _gauss_er(x, sigma_px):
    """Edge response of a Gaussian LSF: the normal CDF, 0.5 (1 + erf(x / (sigma sqrt 2)))."""
    return 0.5 * (1.0 + erf(np.asarray(x) / (sigma_px * math.sqrt(2.0))))


# ---------------------------------------------------------------- edge response
def test_ideal_pixel_edge_is_a_one_pixel_ramp():
    f = np.linspace(0, 400, 400001)  # sinc MTF, signed: truncation error ~ 1 / (2 pi^2 400)
    x = np.array([-1.5, -0.5, -0.3, 0.0, 0.1, 0.4, 0.5, 2.0])
    er = q.edge_response_from_mtf(f, np.sinc(f), x)
    ramp = np.clip(x + 0.5, 0.0, 1.0)
    assert er == pytest.approx(ramp, abs=2e-3)
    assert q.rer(f, np.sinc(f)) == pytest.approx(1.0, abs=2e-3)


@given(st.floats(0.3, 2.0), st.floats(-3.0, 3.0))
@settings(max_examples=30, deadline=None)
def test_gaussian_edge_response_is_erf(sigma, x):
    f = np.linspace(0, 3.0 / sigma, 3001)
    er = q.edge_response_from_mtf(f, _gauss_mtf(f, sigma), x)
    assert float(er) == pytest.approx(float(_gauss_er(x, sigma)), abs=1e-6)


def test_rer_of_gaussian_closed_form():
    sigma = 0.6
    f = np.linspace(0, 5, 5001)
    assert q.rer(f, _gauss_mtf(f, sigma)) == pytest.approx(math.erf(0.5 / (sigma * math.sqrt(2))), abs=1e-7)


def test_overshoot_monotone_edge_is_value_at_1_25_px():
    sigma = 0.7
    f = np.linspace(0, 5, 5001)
    assert q.overshoot(f, _gauss_mtf(f, sigma)) == pytest.approx(float(_gauss_er(1.25, sigma)), abs=1e-7)


def test_sharpened_edge_overshoot_and_transfer():
    """Kernel [-a, 1 + 2a, -a] along x: ER_s(x) = (1 + 2a) ER(x) - a ER(x - 1) - a ER(x + 1)."""
    sigma, a = 0.8, 0.6
    kernel = [[-a, 1 + 2 * a, -a]]
    f = np.linspace(0, 4, 8001)
    mtf_s = _gauss_mtf(f, sigma) * q.kernel_transfer(kernel, f, axis="act")
    xs = q.OVERSHOOT_X_PX
    closed = (1 + 2 * a) * _gauss_er(xs, sigma) - a * _gauss_er(xs - 1, sigma) - a * _gauss_er(xs + 1, sigma)
    assert q.edge_response_from_mtf(f, mtf_s, xs) == pytest.approx(closed, abs=1e-6)
    assert np.any(np.diff(closed) < 0)  # this edge rings: H is the maximum, above 1
    assert q.overshoot(f, mtf_s) == pytest.approx(float(np.max(closed)), abs=1e-6)
    assert q.overshoot(f, mtf_s) > 1.0
    # along the other axis this 1-row kernel does nothing
    assert q.kernel_transfer(kernel, f, axis="alt") == pytest.approx(np.ones_like(f))


def test_edge_response_refuses_bad_input():
    f = np.linspace(0, 1, 101)
    with pytest.raises(InputError, match=r"mtf\[0\]"):
        q.edge_response_from_mtf(f, 0.5 * np.ones_like(f), 0.5)
    with pytest.raises(InputError, match="f_cy_per_px"):
        q.edge_response_from_mtf(f[1:], np.ones(100), 0.5)
    with pytest.raises(InputError, match="too coarse"):
        q.edge_response_from_mtf(np.linspace(0, 1, 5), np.ones(5), 3.0)
    with pytest.raises(InputError, match="phase"):
        q.edge_response_from_mtf(f, np.exp(1j * f), 0.5)


# ---------------------------------------------------------------- noise gain
def test_noise_gain():
    assert q.noise_gain(None) == 1.0
    assert q.noise_gain([[0, 0, 0], [0, 1, 0], [0, 0, 0]]) == 1.0
    assert q.noise_gain([-0.5, 2.0, -0.5]) == pytest.approx(math.sqrt(0.25 + 4 + 0.25))
    assert q.noise_gain(np.ones((3, 3))) == pytest.approx(1 / 3)  # box average: noise / 3
    assert q.noise_gain([-1.0, 4.0, -1.0]) == q.noise_gain([-0.5, 2.0, -0.5])  # unit-sum normalisation
    with pytest.raises(InputError, match="non-zero sum"):
        q.noise_gain([1.0, -1.0])


# ---------------------------------------------------------------- GIQE
def test_giqe5_published_check_value():
    # NGA GIQE 5 (2015), Figure 1 case: RER 0.35, GSD 20.8 in, SNR 50 -> NIIRS 5.0
    assert q.giqe5(gsd_in=20.8, rer=0.35, snr=50.0) == pytest.approx(5.02, abs=0.01)


def test_giqe5_hand_computation():
    lr = math.log10(0.5)
    hand = 9.57 - 3.32 * 1.0 + 3.32 * (1 - math.exp(-1.9 / 20)) * lr - 2 * lr**4 - 1.8 / 20
    assert q.giqe5(gsd_in=10.0, rer=0.5, snr=20.0) == pytest.approx(hand, abs=1e-12)


def test_giqe4_hand_computation_both_branches():
    # RER < 0.9: 10.251 - 3.16 log10(10) + 2.817 log10(0.5) - 0.656 * 0.9 - 0.344 / 50 = 5.64571
    assert q.giqe4(gsd_in=10.0, rer=0.5, overshoot=0.9, noise_gain=1.0, snr=50.0) == pytest.approx(5.64571, abs=1e-5)
    # RER >= 0.9: 10.251 - 3.32 + 1.559 * 0 - 0.656 - 0.344 * 2 / 100 = 6.26812
    assert q.giqe4(gsd_in=10.0, rer=1.0, overshoot=1.0, noise_gain=2.0, snr=100.0) == pytest.approx(6.26812, abs=1e-5)


def test_giqe4_noise_coefficient_is_0_344():
    a = q.giqe4(gsd_in=10.0, rer=0.5, overshoot=0.9, noise_gain=1.0, snr=10.0)
    b = q.giqe4(gsd_in=10.0, rer=0.5, overshoot=0.9, noise_gain=2.0, snr=10.0)
    assert a - b == pytest.approx(0.0344, abs=1e-12)


def test_giqe3_hand_computation():
    # 11.81 + 3.32 log10(1 / 10) - 1.48 - 1 / 100 = 7.0
    assert q.giqe3(gsd_in=10.0, rer=1.0, overshoot=1.0, noise_gain=1.0, snr=100.0) == pytest.approx(7.0, abs=1e-12)


def test_off_nadir_gsd_projection():
    # elevation 30 deg: sin = 1/2; GIQE 5 GSD x 2^(1/4), GIQE 4 GSD x 2^(1/2)
    g5 = q.giqe5(gsd_in=10.0, rer=0.4, snr=40.0, elevation_deg=30.0)
    assert g5 == pytest.approx(q.giqe5(gsd_in=10.0 * 2**0.25, rer=0.4, snr=40.0), abs=1e-12)
    g4 = q.giqe4(gsd_in=10.0, rer=0.4, overshoot=0.9, snr=40.0, elevation_deg=30.0)
    assert g4 == pytest.approx(q.giqe4(gsd_in=10.0 * 2**0.5, rer=0.4, overshoot=0.9, snr=40.0), abs=1e-12)


def test_giqe5_rer_weights_the_worse_axis():
    assert q.giqe5_rer(0.5, 0.5) == pytest.approx(0.5)
    assert q.giqe5_rer(0.8, 0.4) == pytest.approx((0.8 * 0.16) ** (1 / 3))
    assert q.giqe5_rer(0.8, 0.4) < math.sqrt(0.8 * 0.4)


@pytest.mark.parametrize(
    "kwargs, key",
    [
        (dict(gsd_in=0.0, rer=0.5, snr=10.0), "gsd_in"),
        (dict(gsd_in=10.0, rer=-0.1, snr=10.0), "rer"),
        (dict(gsd_in=10.0, rer=0.5, snr=0.0), "snr"),
        (dict(gsd_in=10.0, rer=0.5, snr=10.0, elevation_deg=0.0), "elevation_deg"),
    ],
)
def test_giqe_errors_name_the_parameter(kwargs, key):
    with pytest.raises(ConfigError, match=f"{key} = "):
        q.giqe5(**kwargs)


# ---------------------------------------------------------------- a whole system
class _GaussOTF:
    """A separable Gaussian OTF at focal-plane cy/mm with different widths ACT (x) and ALT (y)."""

    def __init__(self, sigma_act_px, sigma_alt_px, pitch_m):
        self.sx_mm, self.sy_mm = sigma_act_px * pitch_m * 1e3, sigma_alt_px * pitch_m * 1e3

    def __call__(self, fx, fy):
        return np.exp(-2 * np.pi**2 * ((self.sx_mm * fx) ** 2 + (self.sy_mm * fy) ** 2))


def test_predict_quality_axes_and_geometric_means(ankarasat3):
    s = ankarasat3.replace({"optics.f_number": 2.0})  # optical cutoff 4.5 cy/px: the Gaussian has died out
    otf = _GaussOTF(0.4, 0.7, s.detector.pitch_x_m)
    r = q.predict_quality(s, otf=otf)
    rer_act, rer_alt = math.erf(0.5 / (0.4 * math.sqrt(2))), math.erf(0.5 / (0.7 * math.sqrt(2)))
    assert r.rer_act == pytest.approx(rer_act, abs=1e-5)
    assert r.rer_alt == pytest.approx(rer_alt, abs=1e-5)
    assert r.rer == pytest.approx(math.sqrt(rer_act * rer_alt), abs=1e-5)
    assert r.overshoot_act == pytest.approx(float(_gauss_er(1.25, 0.4)), abs=1e-5)
    assert r.gsd_in == pytest.approx(s.gsd_m / 0.0254)
    assert r.noise_gain == 1.0 and r.otf_kind == "signed_otf"
    assert r.giqe5 == pytest.approx(q.giqe5(gsd_in=r.gsd_in, rer=q.giqe5_rer(rer_act, rer_alt), snr=r.snr), abs=1e-4)


def test_predict_quality_reference_system(ankarasat3):
    r = q.predict_quality(ankarasat3)
    assert r.rer_alt < r.rer_act  # along-track smear blurs ALT only
    assert r.mtfa_alt < r.mtfa_act < 0.5
    assert 0.3 < r.rer < 0.7 and r.overshoot < 1.0  # no sharpening: no overshoot
    assert 4.0 < r.giqe5 < 6.5 and 4.0 < r.giqe4 < 6.5  # 0.49 m GSD, SNR ~60: NIIRS ~5
    d = json.loads(json.dumps(r.to_dict()))
    assert {"rer_act", "rer_alt", "overshoot", "giqe4", "giqe5", "snr", "gsd_in"} <= set(d)


def test_predict_quality_sharpening_raises_rer_and_noise_gain(ankarasat3):
    kernel = [[0, -0.25, 0], [-0.25, 2.0, -0.25], [0, -0.25, 0]]
    plain = q.predict_quality(ankarasat3)
    sharp = q.predict_quality(ankarasat3, kernel=kernel)
    assert sharp.rer_act > plain.rer_act and sharp.rer_alt > plain.rer_alt
    assert sharp.noise_gain == pytest.approx(math.sqrt(4 + 4 * 0.0625))
    assert sharp.rer_giqe5 == pytest.approx(plain.rer_giqe5)  # GIQE 5 takes the unsharpened RER
