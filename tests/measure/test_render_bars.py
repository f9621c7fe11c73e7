"""The bar-group renderer of _render.py (annular diffraction x pixel x Gaussian), checked against closed forms and
against test_bars._group (Gaussian PSF x pixel box, exact CDF): no satchain code involved."""

from __future__ import annotations

import numpy as np
import pytest
from _render import bar_coltman, bar_esf, render_bar_group
from test_bars import _coltman, _group

DARK, BRIGHT = 40.0, 160.0
MID = (DARK + BRIGHT) / 2


def _tail_constant(q, eps):
    """ESF(-d) -> C / d for large d: the annular MTF falls as 1 - a nu near 0 with a = 4 / (pi (1 - eps))
    (O'Neill), the pixel and the Gaussian are flat there, so ESF(-d) ~ a q / (2 pi^2 d)."""
    return 4 / (np.pi * (1 - eps)) * q / (2 * np.pi**2)


@pytest.mark.parametrize(
    "period, phase, n_bars, s", [(4.0, 0.5, 3, 0.4), (2.5, 0.13, 3, 0.6), (7.3, 0.81, 7, 0.3), (12.0, 0.0, 3, 0.8)]
)
def test_gaussian_only_is_test_bars_group(period, phase, n_bars, s):
    """No diffraction (q = 0): the quadrature ESF equals the exact box * Gaussian CDF, pixel for pixel."""
    img, roi = render_bar_group(period, phase, n_bars, q=0.0, eps=0.0, blur_sigma_px=s, rows=8)
    ref, ref_roi = _group(period, phase, n_bars, s)
    assert roi == ref_roi
    assert img.shape == ref.shape
    np.testing.assert_allclose(img, ref, rtol=0, atol=1e-5)  # spline table: 1e-7 of the range
    assert bar_coltman(1 / period, q=0.0, eps=0.0, blur_sigma_px=s) == pytest.approx(_coltman(1 / period, s), abs=1e-12)


def test_small_q_converges_to_gaussian_linearly():
    """Diffraction with a vanishing Q: the image tends to the Gaussian one, the difference linear in Q (the MTF
    is 1 - a q f near f = 0)."""
    ref, _ = _group(5.0, 0.3, 3, 0.6, rows=4)
    d = [np.abs(render_bar_group(5.0, 0.3, 3, q=q, eps=0.33, blur_sigma_px=0.6)[0] - ref).max() for q in (1e-3, 1e-4)]
    assert d[0] < 0.05
    assert d[1] / d[0] == pytest.approx(0.1, abs=0.01)


@pytest.mark.parametrize("q, eps", [(1.0, 0.33), (1.5, 0.33), (1.2, 0.0)])
def test_esf_symmetry_and_diffraction_tail(q, eps):
    esf = bar_esf(q, eps, 0.0)
    d = np.array([0.3, 2.0, 17.0, 120.0])
    np.testing.assert_allclose(esf(d) + esf(-d), 1.0, atol=1e-12)
    assert esf(np.array([0.0]))[0] == pytest.approx(0.5, abs=1e-12)
    tail = esf(np.array([-150.0, -250.0])) * np.array([150.0, 250.0])
    np.testing.assert_allclose(tail, _tail_constant(q, eps), rtol=0.02)


@pytest.mark.parametrize("period, s", [(2.5, 0.8), (4.0, 0.3), (12.0, 0.6)])
def test_gaussian_plate_and_area(period, s):
    """Far from the group the profile is the dark level; the excess over the plate integrates to the bars'
    area (n P / 2 px at bright - dark): the pixel sinc is 0 at every non-zero integer frequency, so the sum of
    the samples is the integral."""
    img, _ = render_bar_group(period, 0.37, 3, q=0.0, eps=0.0, blur_sigma_px=s, dark=DARK, bright=BRIGHT)
    v = img[0]
    assert v[0] == pytest.approx(DARK, abs=1e-9) and v[-1] == pytest.approx(DARK, abs=1e-9)
    assert np.sum(v - DARK) == pytest.approx((BRIGHT - DARK) * 3 * period / 2, abs=1e-7)


@pytest.mark.parametrize(
    "q, eps, s", [(0.0, 0.0, 0.4), (0.0, 0.0, 0.8), (1.0, 0.33, 0.0), (1.2, 0.33, 0.3), (1.5, 0.33, 0.0)]
)
def test_long_grating(q, eps, s):
    """A 25-bar grating of 4 px with bar centres on pixel centres.  In the middle: (1) the mean over whole
    periods is the mid level (square wave: no even harmonics; P integer: the aliases of the mean sit at integer
    frequencies, where the pixel sinc is 0), short by at most the diffraction tails of the two missing
    semi-infinite gratings, (mid - dark) C (1/D1 + 1/D2); (2) the peak-to-trough modulation over bright - dark
    is Coltman's square-wave CTF (a Fourier series, computed apart from the ESF quadrature)."""
    period, n = 4.0, 25
    img, _ = render_bar_group(period, 0.0, n, q=q, eps=eps, blur_sigma_px=s, dark=DARK, bright=BRIGHT)
    v = img[0]
    start = 3 * period  # first bar [12, 14]: centres at 13 + 4 k
    c = int(start + period / 4 + (n // 2) * period)
    win = v[c - 20 : c + 20]
    ends = (start - period / 4, start + (n - 1) * period + 3 * period / 4)  # each bar owns one period
    tails = (MID - DARK) * _tail_constant(q, eps) * sum(1 / abs(c - e) for e in ends)
    assert abs(win.mean() - MID) <= 1.2 * tails + 1e-9, (win.mean() - MID, tails)
    if q > 0:
        assert abs(win.mean() - MID) >= 0.8 * tails  # the tails are there, and of the size the MTF slope says
    ctf = bar_coltman(1 / period, q=q, eps=eps, blur_sigma_px=s)
    assert (v[c] - v[c + 2]) / (BRIGHT - DARK) == pytest.approx(ctf, abs=1e-4)
