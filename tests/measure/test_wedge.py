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
