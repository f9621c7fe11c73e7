"""Siemens star on stars whose modulation at each radius is set by a known MTF."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _render import annular_mtf
from hypothesis import example, given, settings
from hypothesis import strategies as st

from satchain.errors import InputError, SatchainError
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
    for k in ("ACT", "ALT", "D45", "D135"):  # amplitude quadratic across each band: 1e-4 (a constant one: 0.009)
        assert np.max(np.abs(r.mtf[k] - truth)) < 0.003, k
    assert r.mtf_at_nyquist["ACT"] == pytest.approx(np.exp(-2 * np.pi**2 * s**2 * 0.25), abs=0.002)
    assert 0.7 < r.f_cy_per_px.max() <= 0.75


def test_directions_follow_the_axes():
    """Blur along x only lowers the ACT MTF (tangent along x: sectors above/below the centre)."""
    r = measure_star(_star(0.9, 0.3), cycles=N, input_modulation=0.4)
    f = r.f_cy_per_px
    band = f <= 0.5
    # a 45-deg sector sees tangents within +-22.5 deg of its axis: the truth is the sector mean
    phi = np.linspace(-np.pi / 8, np.pi / 8, 181)[:, None]
    act = np.exp(-2 * np.pi**2 * f**2 * (0.81 * np.cos(phi) ** 2 + 0.09 * np.sin(phi) ** 2)).mean(axis=0)
    alt = np.exp(-2 * np.pi**2 * f**2 * (0.09 * np.cos(phi) ** 2 + 0.81 * np.sin(phi) ** 2)).mean(axis=0)
    # the amplitude changes by ~30 % across the ALT sector at 0.4 cy/px; fitted as quadratic in the angle to the
    # axis and reported as its uniform mean: 0.004 (a constant amplitude per 1-px annulus: 0.06)
    assert np.max(np.abs(r.mtf["ACT"][band] - act[band])) < 0.01
    assert np.max(np.abs(r.mtf["ALT"][band] - alt[band])) < 0.01
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


# ---------------------------------------------------------------- issue 10: centre, cycles, input modulation, 1-sigma

DIRS = {"ACT": 0.0, "D45": 45.0, "ALT": 90.0, "D135": 135.0}
SUB = 4  # sub-samples per pixel side


def _box(u):
    """Transfer function of the mean of SUB equally spaced point samples across one pixel."""
    u = np.asarray(u, dtype=float)
    den = SUB * np.sin(np.pi * u / SUB)
    return np.where(np.abs(u) < 1e-12, 1.0, np.sin(np.pi * u) / np.where(den == 0, 1.0, den))


def _render_star(n, centre, mtf, size=121, mean=100.0, amp=40.0):
    """Sinusoidal star, isotropically blurred by ``mtf`` and integrated over each pixel (SUB x SUB samples).

    The isotropic blur of cos(n th) is cos(n th) h(r) with h(r) = n int M(rho) J_n(2 pi rho r) drho / rho
    (Hankel transform); h(r) = M(n / (2 pi r)) to 0.001 at r >= 15 px and 0.003 at r = 10 px (checked for
    both MTFs below), so the local-grating value is used (fast)."""
    sub = (np.arange(SUB) + 0.5) / SUB - 0.5
    y, x = np.mgrid[0:size, 0:size].astype(float)
    out = np.zeros((size, size))
    for dy in sub:
        for dx in sub:
            xx, yy = x + dx - centre[0], y + dy - centre[1]
            r = np.maximum(np.hypot(xx, yy), 1e-9)
            out += mean + amp * mtf(n / (2 * np.pi * r)) * np.cos(n * np.arctan2(yy, xx))
    return out / SUB**2


def _truth(f, mtf, axis_deg, half=np.pi / 8):
    """Sector mean (frequency directions within +-22.5 deg of the axis) of optics x pixel-sampling MTF."""
    phi = np.deg2rad(axis_deg) + np.linspace(-half, half, 91)[:, None]
    return (mtf(f) * _box(f * np.cos(phi)) * _box(f * np.sin(phi))).mean(axis=0)


MTFS = {
    "gaussian": lambda f: np.exp(-2 * np.pi**2 * 0.5**2 * f**2),  # Gaussian-like (MTF(0) flat)
    "annular": lambda f: annular_mtf(f * 1.2, 0.3),  # diffraction, Q = 1.2, 30 % obscuration (linear at 0)
}


@settings(max_examples=6, deadline=None)
@given(
    dx=st.floats(-1.5, 1.5),
    dy=st.floats(-1.5, 1.5),
    kind=st.sampled_from(sorted(MTFS)),
)
# centres on or near a pixel centre: a constant amplitude per 1-px annulus was off by up to 0.021 there
@example(dx=0.0, dy=0.0, kind="gaussian")
@example(dx=0.0, dy=1 / 32, kind="gaussian")
@example(dx=0.0, dy=0.5, kind="gaussian")
@example(dx=1 / 32, dy=0.0, kind="annular")
def test_exact_star_centre_and_modulation_unknown(dx, dy, kind):
    """Centre not given (and off the region centre by up to 1.5 px), input modulation not given: every
    direction within 0.02 of the true MTF up to Nyquist (issue 10's criterion), the centre to 0.01 px."""
    n, mtf = 32, MTFS[kind]
    centre = (60.0 + dx, 60.0 + dy)
    r = measure_star(_render_star(n, centre, mtf), cycles=n)
    assert r.center_from == "estimated"
    assert abs(r.center_xy_px[0] - centre[0]) < 0.01 and abs(r.center_xy_px[1] - centre[1]) < 0.01
    assert r.input_modulation == pytest.approx(0.4, rel=0.015)
    ok = r.f_cy_per_px <= 0.5
    assert r.f_cy_per_px.max() > 0.5
    for k, a in DIRS.items():
        err = np.abs(r.mtf[k] - _truth(r.f_cy_per_px, mtf, a))[ok]
        assert err.max() < 0.01, (k, err.max())  # issue 10 asks 0.02; <= 0.003 over 46 centres (README)


def test_half_pixel_centre_error_is_refined():
    """The issue's case: a given centre 0.5 px off. Refined, MTF@Nyquist is right; unrefined it is not."""
    n, mtf = 32, MTFS["gaussian"]
    img = _render_star(n, (60.2, 59.9), mtf)
    true_nyq = float(_truth(np.array([0.5]), mtf, 0.0)[0])
    r = measure_star(img, cycles=n, center=(60.7, 59.9), input_modulation=0.4)
    assert r.center_from == "refined" and abs(r.center_xy_px[0] - 60.2) < 0.01
    assert r.mtf_at_nyquist["ACT"] == pytest.approx(true_nyq, abs=0.02)
    bad = measure_star(img, cycles=n, center=(60.7, 59.9), input_modulation=0.4, refine_center=False)
    assert abs(bad.mtf_at_nyquist["ACT"] - true_nyq) > 0.03  # what the refinement fixes (tangent along x)


def test_uncertainty_is_honest():
    """Across noisy realisations the true MTF@Nyquist (each direction) lies within +-2 sigma ~95 % of the time,
    and the centre's error over its 1-sigma has unit rms."""
    n, mtf = 32, MTFS["gaussian"]
    clean = _render_star(n, (60.3, 59.6), mtf)
    rng = np.random.default_rng(7)
    truth = {k: float(_truth(np.array([0.5]), mtf, a)[0]) for k, a in DIRS.items()}
    inside, z = [], []
    for _ in range(15):
        r = measure_star(clean + rng.normal(0, 4.0, clean.shape), cycles=n)
        for k in DIRS:
            inside.append(abs(r.mtf_at_nyquist[k] - truth[k]) <= 2 * r.mtf_at_nyquist_std[k])
        z += [(r.center_xy_px[0] - 60.3) / r.center_std_px[0], (r.center_xy_px[1] - 59.6) / r.center_std_px[1]]
    assert 0.6 < np.sqrt(np.mean(np.square(z))) < 1.5  # the centre's 1-sigma is its scatter
    frac = np.mean(inside)
    assert 0.85 <= frac <= 1.0, frac
    assert 0.01 < r.mtf_at_nyquist_std["ACT"] < 0.2


def test_refusals_and_flags():
    n, mtf = 32, MTFS["gaussian"]
    img = _render_star(n, (60.0, 60.0), mtf)
    with pytest.raises(InputError, match="32 cycles"):  # wrong --cycles names the count found
        measure_star(img, cycles=24)
    with pytest.raises(InputError, match="32 cycles"):
        measure_star(img, cycles=64)
    noise = np.random.default_rng(1).normal(100, 3, img.shape)
    with pytest.raises(InputError):
        measure_star(noise, cycles=n)  # no star at all
    with pytest.raises(InputError, match="MTF would reach"):
        measure_star(img, cycles=n, input_modulation=0.2)  # MTF > 1.2 is never reported
    clipped = np.minimum(img + np.random.default_rng(2).normal(0, 0.5, img.shape), 130.0)
    assert any(f.startswith("clipping") for f in measure_star(clipped, cycles=n).flags)
    y, x = np.mgrid[0:121, 0:121]
    ramp = img * (1 + 0.004 * (x - 60))  # 50 % illumination gradient across the star
    assert any("non-uniform illumination" in f for f in measure_star(ramp, cycles=n).flags)
    assert measure_star(img, cycles=n).flags == ()
    low = img + np.random.default_rng(3).normal(0, 8.0, img.shape)
    assert any("contrast-to-noise" in f for f in measure_star(low, cycles=n, input_modulation=0.4).flags)
    with pytest.raises(InputError, match="cannot be extrapolated"):  # too noisy to extrapolate to f = 0
        measure_star(low, cycles=n)


# -------------------------------------------------------- issue 18: a given centre a few px off; input_modulation


@settings(max_examples=6, deadline=None)
@given(dist=st.floats(0.5, 5.0), angle=st.floats(0.0, 360.0, exclude_max=True))
@example(dist=3.0, angle=0.0)  # the audit's case: refused with a message about --cycles
@example(dist=5.0, angle=225.0)
def test_given_centre_a_few_px_off_is_found(dist, angle):
    """A given centre up to 5 px off in any direction: the coarse search finds the star's centre and the MTF is
    the true one (as with the exact centre) within 0.01 up to Nyquist in every direction."""
    n, mtf, centre = 32, MTFS["gaussian"], (60.3, 59.6)
    img = _render_star(n, centre, mtf)
    t = np.deg2rad(angle)
    given_xy = (centre[0] + dist * np.cos(t), centre[1] + dist * np.sin(t))
    r = measure_star(img, cycles=n, center=given_xy, input_modulation=0.4)
    assert r.center_from == "refined"
    assert abs(r.center_xy_px[0] - centre[0]) < 0.01 and abs(r.center_xy_px[1] - centre[1]) < 0.01
    ok = r.f_cy_per_px <= 0.5
    ref = measure_star(img, cycles=n, center=centre, input_modulation=0.4)  # the true centre given
    for k, a in DIRS.items():
        assert np.max(np.abs(r.mtf[k] - _truth(r.f_cy_per_px, mtf, a))[ok]) < 0.01, k
        assert np.all(np.abs(r.mtf[k] - ref.mtf[k]) <= np.maximum(2 * ref.mtf_std[k], 1e-4)), k  # same as given


def test_centre_too_far_off_is_refused_about_the_centre():
    n, mtf = 32, MTFS["gaussian"]
    img = _render_star(n, (60.3, 59.6), mtf)
    with pytest.raises(InputError, match=r"center = \(72.3, 59.6\).*within 6 px") as exc:
        measure_star(img, cycles=n, center=(72.3, 59.6), input_modulation=0.4)
    assert "cycles" not in str(exc.value).replace("-cycle star", "")
    with pytest.raises(InputError, match="32 cycles"):  # a wrong --cycles with a good centre still names the count
        measure_star(img, cycles=24, center=(61.0, 60.0))


@pytest.mark.parametrize("bad", [5.0, 0.0, -0.4, 1.0001, float("nan"), float("inf"), True, "0.4x"])
def test_input_modulation_outside_0_1_is_refused(bad):
    """The audit's `measure star --input-modulation 5` silently divided the MTF by 5."""
    with pytest.raises(SatchainError, match=r"input_modulation = .*\(0, 1\]"):
        measure_star(_star(0.5, 0.5), cycles=N, input_modulation=bad)
