"""Wedge contrast scan on stripes rendered exactly (Fourier series) with a Gaussian blur."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from satchain.errors import InputError
from satchain.measure.wedge import measure_wedge

SIGMA = 0.8


def _mtf(f):
    return np.exp(-2 * np.pi**2 * SIGMA**2 * np.asarray(f) ** 2)


def _ctf(f):
    k = np.arange(1, 200, 2)
    return 4 / np.pi * np.sum((-1.0) ** ((k - 1) // 2) * _mtf(np.outer(np.atleast_1d(f), k)) / k, axis=1)


def _lw(p):
    return 3.0 - 0.01 * p  # line width 3 px -> 1 px over 200 columns


def _render(rows=64, cols=200):
    y = np.arange(rows)[:, None]
    period = 2 * _lw(np.arange(cols, dtype=float))[None, :]
    k = np.arange(1, 200, 2)[:, None, None]
    # stripes along x (ALT resolution), 50 % duty cycle, mean 0.5, unit peak-to-peak before blur
    wave = 2 / np.pi * np.sum(_mtf(k / period) * np.sin(2 * np.pi * k * y / period) / k, axis=0)
    return 0.5 + wave


def test_threshold_line_width_matches_ctf_prediction():
    img = _render()
    r = measure_wedge(img, line_width_px=_lw, average_px=1, pixel_m=0.49)
    f15 = brentq(lambda f: _ctf(f)[0] - 0.15, 0.05, 0.5)
    assert r.resolved_line_width_px == pytest.approx(1 / (2 * f15), rel=0.04)
    assert r.resolved_f_cy_per_px == pytest.approx(1 / (2 * r.resolved_line_width_px))
    assert r.resolved_line_width_m == pytest.approx(0.49 * r.resolved_line_width_px)
    assert r.contrast[0] > 0.5 and np.all(np.diff(r.line_width_px) <= 0)


def test_act_orientation_and_unresolved():
    img = _render()
    r = measure_wedge(img.T, line_width_px=_lw, direction="ACT")
    assert r.resolved_line_width_px == pytest.approx(measure_wedge(img, line_width_px=_lw).resolved_line_width_px)
    none = measure_wedge(img, line_width_px=_lw, threshold=0.01)
    assert none.resolved_line_width_px is None and none.to_dict()["resolved_f_cy_per_px"] is None


def test_wedge_bad_inputs():
    with pytest.raises(InputError):
        measure_wedge(_render(), line_width_px=np.ones(5))
    with pytest.raises(ValueError):
        measure_wedge(_render(), line_width_px=_lw, threshold=1.5)


def test_wedge_refuses_no_wedge():
    """Issue 10: a constant image reported a resolution (1.249 m); now refused, as is pure noise."""
    with pytest.raises(InputError, match="no wedge"):
        measure_wedge(np.full((64, 200), 0.5), line_width_px=_lw, pixel_m=0.49)
    noise = 0.5 + np.random.default_rng(0).normal(0, 0.02, (64, 200))
    with pytest.raises(InputError, match="no wedge"):
        measure_wedge(noise, line_width_px=_lw)
    with pytest.raises(InputError, match="already"):  # the wide end below the threshold
        measure_wedge(_render(), line_width_px=_lw, threshold=0.99)


def test_wedge_uncertainty_covers_the_noise():
    """Across noisy realisations the noise-free resolution lies within +-2 sigma (>= 85 %), and sigma is not
    wildly inflated (under 3x the scatter); a noise floor near the threshold is flagged."""
    img = _render()
    ref = measure_wedge(img, line_width_px=_lw).resolved_line_width_px
    rng = np.random.default_rng(3)
    vals, sds = [], []
    for _ in range(30):
        r = measure_wedge(img + rng.normal(0, 0.02, img.shape), line_width_px=_lw, average_px=5)
        assert r.noise_std == pytest.approx(0.02, rel=0.3)
        vals.append(r.resolved_line_width_px)
        sds.append(r.resolved_line_width_px_std)
    vals, sds = np.array(vals), np.array(sds)
    assert np.mean(np.abs(vals - ref) <= 2 * sds) >= 0.85
    assert np.median(sds) < 3 * max(np.std(vals), 0.005)
    noisy = measure_wedge(img + rng.normal(0, 0.03, img.shape), line_width_px=_lw)
    assert any("noise floor" in f for f in noisy.flags)
