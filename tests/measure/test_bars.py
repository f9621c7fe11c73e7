"""Bar targets rendered exactly (Fourier series of the blurred square wave) with a Gaussian system MTF."""

from __future__ import annotations

import numpy as np
import pytest

from satchain.measure.bars import coltman_inverse_coefficients, measure_bars, mtf_from_ctf_samples

SIGMA = 0.6


def _mtf(f):
    return np.exp(-2 * np.pi**2 * SIGMA**2 * f**2) * np.abs(np.sinc(f))  # Gaussian x 100 % pixel


def _ctf_true(f):
    """Coltman (1954) forward series: CTF(f) = 4/pi sum_k odd (-1)^((k-1)/2) MTF(k f) / k."""
    k = np.arange(1, 400, 2)
    return 4 / np.pi * np.sum((-1.0) ** ((k - 1) // 2) * _mtf(np.outer(f, k)) / k, axis=1)


def _render(periods, rows=20, mean=100.0, amp=60.0):
    """Bars along y (profile along x) of each period, peaks on pixel centres; pixel aperture included."""
    blocks, rois, x0 = [], [], 0
    for p in periods:
        n = int(4 * p)
        x = np.arange(n) - p / 4  # a sample on each bright-bar centre
        k = np.arange(1, 400, 2)
        wave = 4 / np.pi * np.sum(_mtf(k / p)[None, :] * np.sin(2 * np.pi * np.outer(x, k) / p) / k, axis=1)
        blocks.append(np.tile(mean + amp * wave, (rows, 1)))
        rois.append((x0, 0, x0 + n, rows))
        x0 += n
    return np.hstack(blocks), rois


def test_ctf_and_inverse_coltman():
    periods = np.array([40, 24, 16, 12, 10, 8, 6, 5, 4, 3, 2.0])
    img, rois = _render(periods)
    r = measure_bars(img, periods_px=periods, group_rois=rois, levels=(40.0, 160.0))
    f = 1 / periods
    even = (periods % 2 == 0) & (periods >= 4)  # samples hit the peaks and the troughs exactly
    np.testing.assert_allclose(r.ctf[even], _ctf_true(f[even]), atol=1e-6)
    assert r.large_area_contrast == pytest.approx(0.6)
    low = even & (f <= 0.25)  # sampled peaks exact, and the groups cover k f well enough for the series
    np.testing.assert_allclose(r.mtf[low], _mtf(f[low]), atol=0.03)


def test_inverse_series_round_trip_on_samples():
    f = np.linspace(0.01, 1.2, 400)
    m = mtf_from_ctf_samples(f, _ctf_true(f))
    np.testing.assert_allclose(m[f < 0.6], _mtf(f[f < 0.6]), atol=2e-3)
    assert [k for k, _ in coltman_inverse_coefficients(10)] == [1, 3, 5, 7, 11, 13, 15, 17, 19]


def test_against_satchain_ctf_if_present():
    ctf = pytest.importorskip("satchain.ctf")
    if not hasattr(ctf, "mtf_from_ctf"):
        pytest.skip("satchain.ctf.mtf_from_ctf not available")
    f = np.linspace(0.02, 0.5, 25)
    ref = np.asarray(ctf.mtf_from_ctf(f, _ctf_true))
    fine = np.linspace(0.005, 3.0, 3000)
    mine = np.interp(f, fine, mtf_from_ctf_samples(fine, _ctf_true(fine)))
    np.testing.assert_allclose(mine, ref, atol=3e-3)
