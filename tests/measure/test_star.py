"""Siemens star on stars whose modulation at each radius is set by a known MTF."""

from __future__ import annotations

import json

import numpy as np
import pytest

from satchain.errors import InputError
from satchain.measure.star import measure_star

N = 48


def _star(sx, sy, size=241, mean=100.0, amp=40.0, center=None):
    """Sinusoidal star whose local grating (frequency n / 2 pi r along the tangent) is attenuated by the
    Gaussian MTF exp(-2 pi^2 (sx^2 fx^2 + sy^2 fy^2)), sampled at pixel centres (y downwards)."""
    cx, cy = ((size - 1) / 2,) * 2 if center is None else center
    y, x = np.mgrid[0:size, 0:size].astype(float)
    x, y = x - cx, y - cy
    r, th = np.hypot(x, y), np.arctan2(y, x)
    f = N / (2 * np.pi * np.maximum(r, 1e-9))
    fx, fy = -np.sin(th) * f, np.cos(th) * f
    g = np.exp(-2 * np.pi**2 * (sx**2 * fx**2 + sy**2 * fy**2))
    return mean + amp * g * np.cos(N * th)


def test_isotropic_gaussian_all_directions():
    s = 0.7
    r = measure_star(_star(s, s), cycles=N, input_modulation=0.4)
    truth = np.exp(-2 * np.pi**2 * s**2 * r.f_cy_per_px**2)
    for k in ("ACT", "ALT", "D45", "D135"):  # 1-px annuli at radii down to 10 px: 0.01
        assert np.max(np.abs(r.mtf[k] - truth)) < 0.01, k
    assert r.mtf_at_nyquist["ACT"] == pytest.approx(np.exp(-2 * np.pi**2 * s**2 * 0.25), abs=0.005)
    assert 0.7 < r.f_cy_per_px.max() <= 0.75


def test_directions_follow_the_axes():
    """Blur along x only lowers the ACT MTF (tangent along x: sectors above/below the centre)."""
    r = measure_star(_star(0.9, 0.3), cycles=N, input_modulation=0.4)
    f = r.f_cy_per_px
    band = (f > 0.2) & (f < 0.4)
    # a 45-deg sector sees tangents within +-22.5 deg of its axis: the truth is the sector mean
    phi = np.linspace(-np.pi / 8, np.pi / 8, 181)[:, None]
    act = np.exp(-2 * np.pi**2 * f**2 * (0.81 * np.cos(phi) ** 2 + 0.09 * np.sin(phi) ** 2)).mean(axis=0)
    alt = np.exp(-2 * np.pi**2 * f**2 * (0.09 * np.cos(phi) ** 2 + 0.81 * np.sin(phi) ** 2)).mean(axis=0)
    assert np.max(np.abs(r.mtf["ACT"][band] - act[band])) < 0.04
    assert np.max(np.abs(r.mtf["ALT"][band] - alt[band])) < 0.04
    assert np.all(r.mtf["ACT"][band] < r.mtf["D45"][band])
    assert np.all(r.mtf["D45"][band] < r.mtf["ALT"][band])
    np.testing.assert_allclose(r.mtf["D45"], r.mtf["D135"], atol=1e-6)  # symmetric blur


def test_input_modulation_estimate_and_offcentre_roi():
    img = np.full((300, 320), 100.0)
    img[20:261, 50:291] = _star(0.5, 0.5)
    r = measure_star(img, cycles=N, roi=(50, 20, 291, 261), pixel_m=0.5)
    # the star's own modulation is 0.4; the estimate extrapolates the outer radii (f >= 0.064 cy/px) linearly to
    # f = 0. A Gaussian MTF is flat at 0, the worst case for a straight line: within 5 % (an optical MTF, linear
    # near 0, does better: see test_auto and the README)
    assert r.input_modulation == pytest.approx(0.4, rel=0.05)
    np.testing.assert_allclose(r.f_cy_per_m_ground, r.f_cy_per_px / 0.5)
    json.dumps(r.to_dict(), allow_nan=False)


def test_star_bad_inputs():
    with pytest.raises(InputError):
        measure_star(np.full((24, 24), 5.0), cycles=N)  # too small for 48 cycles at 0.75 cy/px
    with pytest.raises(InputError):
        measure_star(np.full((241, 241), 5.0), cycles=N)  # flat: no modulation
    with pytest.raises(ValueError):
        measure_star(_star(0.5, 0.5), cycles=2)
