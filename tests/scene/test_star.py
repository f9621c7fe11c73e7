"""Sine Siemens star: pixel averages against closed forms, brute force and cycle counts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from satchain.errors import ConfigError
from satchain.scene.layout import Scene
from satchain.scene.star import sine_star_average
from satchain.scene.targets import SiemensStar


@pytest.mark.parametrize("cycles", [1, 3, 8, 13])
def test_quadrant_integral_closed_form(cycles):
    """Centre on a pixel corner: the pixels with x > cx, y > cy are the quadrant theta in (0, pi/2), whose
    integral of sin(k theta) over the annulus is (R^2 - r^2) / 2 * (1 - cos(k pi / 2)) / k."""
    p, r_in, R = 0.25, 0.6, 3.1
    s = sine_star_average((0, 0, 32, 32), pixel_m=p, center_m=(4.0, 4.0), cycles=cycles,
                          inner_radius_m=r_in, radius_m=R)  # fmt: skip
    quadrant = s[16:, 16:].sum() * p * p
    expect = (R**2 - r_in**2) / 2 * (1 - math.cos(cycles * math.pi / 2)) / cycles
    assert quadrant == pytest.approx(expect, abs=1e-9)
    assert s.sum() == pytest.approx(0.0, abs=1e-9)  # whole cycles around the full annulus


def test_pixels_against_supersampling():
    p, c, k, r_in, R = 0.25, (5.1, 4.7), 12, 0.8, 4.0
    s = sine_star_average((0, 0, 40, 40), pixel_m=p, center_m=c, cycles=k, inner_radius_m=r_in, radius_m=R)
    n = 500
    g = (np.arange(n) + 0.5) / n
    for i, j in [(15, 16), (10, 20), (18, 35), (30, 30), (22, 18), (2, 2)]:
        xx, yy = np.meshgrid((j + g) * p - c[0], (i + g) * p - c[1])
        r = np.hypot(xx, yy)
        ref = (np.sin(k * np.arctan2(yy, xx)) * ((r >= r_in) & (r <= R))).mean()
        assert abs(s[i, j] - ref) < 2e-5  # 500 x 500 midpoint supersampling error ~1e-5


def test_star_cycles_from_sign_changes():
    star = SiemensStar("s", center_m=(20.0, 20.0), radius_m=15.0, cycles=24, inner_radius_m=1.0)
    p = 0.1
    img = Scene(40.0, 40.0, (star,), background=0.2).render(pixel_m=p).astype(float)
    for radius in (6.0, 10.0, 13.0):
        a = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
        rows = np.floor((20.0 + radius * np.sin(a)) / p).astype(int)
        cols = np.floor((20.0 + radius * np.cos(a)) / p).astype(int)
        v = img[rows, cols] - star.mean
        changes = np.count_nonzero(np.sign(v) != np.sign(np.roll(v, 1)))
        assert changes == 2 * star.cycles


def test_star_values_bounded_and_mean_preserved():
    star = SiemensStar("s", center_m=(10.0, 10.0), radius_m=8.0, cycles=16, inner_radius_m=0.5)
    p = 0.2
    img = Scene(20.0, 20.0, (star,), background=0.2).render(pixel_m=p).astype(float)
    lo, hi = star.mean - star.amplitude, star.mean + star.amplitude
    assert img.min() >= min(lo, 0.2) - 1e-6 and img.max() <= hi + 1e-6
    # total reflectance: background outside the disc + mean inside (the sine integrates to zero)
    total = img.sum() * p * p
    expect = 0.2 * (400 - math.pi * 64) + star.mean * math.pi * 64
    assert total == pytest.approx(expect, rel=1e-5)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"inner_radius_m": 0.0}, "inner_radius_m"),
        ({"inner_radius_m": 30.0}, "inner_radius_m"),
        ({"cycles": 0}, "cycles"),
        ({"amplitude": 0.9}, "amplitude"),
        ({"radius_m": -1.0}, "radius_m"),
    ],
)
def test_bad_star(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        SiemensStar("s", **kwargs)


def _gauss_pixel_average(i, j, p, c, k, n=32):
    """The test's own reference for a pixel wholly inside the annulus: an n x n tensor Gauss-Legendre rule
    over the pixel (the integrand is smooth there; 32 points per axis resolve ~10 rad of phase per pixel)."""
    x, wt = np.polynomial.legendre.leggauss(n)
    u, wu = (x + 1) / 2, wt / 2
    xx, yy = np.meshgrid((j + u) * p - c[0], (i + u) * p - c[1])
    return float(wu @ np.sin(k * np.arctan2(yy, xx)) @ wu)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    cycles=st.integers(1, 64),
    fx=st.floats(0.0, 1.0),
    fy=st.floats(0.0, 1.0),
    radius_px=st.floats(20.0, 300.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_annulus_pixels_against_tensor_gauss(cycles, fx, fy, radius_px, seed):
    """Pixels wholly inside the annulus, at every distance from the centre (every quadrature rule and block
    kind of the renderer), against a 32 x 32 Gauss-Legendre average per pixel, to the stated accuracy."""
    p = 0.1
    size = int(2 * radius_px) + 4
    c = ((size / 2 + fx) * p, (size / 2 + fy) * p)
    r_in, R = 1.3 * p, radius_px * p
    s = sine_star_average((0, 0, size, size), pixel_m=p, center_m=c, cycles=cycles, inner_radius_m=r_in,
                          radius_m=R)  # fmt: skip
    rng = np.random.default_rng(seed)
    checked = 0
    while checked < 25:
        i, j = rng.integers(0, size, 2)
        corners = np.hypot((j + np.array([0, 1, 0, 1])) * p - c[0], (i + np.array([0, 0, 1, 1])) * p - c[1])
        near = np.hypot(np.clip(c[0], j * p, (j + 1) * p) - c[0], np.clip(c[1], i * p, (i + 1) * p) - c[1])
        if near < r_in or corners.max() > R:
            continue
        r = corners.min()
        assert abs(s[i, j] - _gauss_pixel_average(i, j, p, c, cycles)) < 1e-9 * max(1.0, r / p)
        checked += 1


@pytest.mark.parametrize("cycles", [32, 7])
def test_large_star_quadrant_and_supersampled_rim(cycles):
    """A star 600 px across (blocks wholly inside, outside and across both circles): the closed-form quadrant
    integral, and pixels on the rims against 1000 x 1000 midpoint supersampling."""
    p, r_in, R = 0.05, 0.5, 15.0
    c = (16.0, 16.0)  # on a pixel corner
    s = sine_star_average((0, 0, 640, 640), pixel_m=p, center_m=c, cycles=cycles, inner_radius_m=r_in,
                          radius_m=R)  # fmt: skip
    quadrant = s[320:, 320:].sum() * p * p
    assert quadrant == pytest.approx((R**2 - r_in**2) / 2 * (1 - math.cos(cycles * math.pi / 2)) / cycles, abs=1e-8)
    left = (math.cos(cycles * math.pi / 2) - math.cos(cycles * 3 * math.pi / 2)) / cycles  # theta in (pi/2, 3pi/2)
    assert s[:, :320].sum() * p * p == pytest.approx((R**2 - r_in**2) / 2 * left, abs=1e-8)
    n = 1000
    g = (np.arange(n) + 0.5) / n
    on_rims = [(c[1] + rad * math.sin(a), c[0] + rad * math.cos(a)) for rad in (r_in, R) for a in (0.3, 2.0, 4.4)]
    for i, j in [(int(y / p), int(x / p)) for y, x in on_rims]:
        xx, yy = np.meshgrid((j + g) * p - c[0], (i + g) * p - c[1])
        r = np.hypot(xx, yy)
        ref = (np.sin(cycles * np.arctan2(yy, xx)) * ((r >= r_in) & (r <= R))).mean()
        assert abs(s[i, j] - ref) < 5e-6
