"""Staggered arrays (issue 32 point 5): the quincunx lattice's aliases and Nyquist, the combination's transfer
function, and the MTF measured on edges rendered here (an exact Gaussian-blurred edge integrated over each
p-wide pixel) against the prediction, beyond a single array's Nyquist."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.special import ndtr

from satchain.engine.staggered import combine_staggered, staggered_samples
from satchain.measure.edge import measure_edge
from satchain.tf.staggered import alias_offsets_cy_per_mm, combination_otf, nyquist_cy_per_mm, unaliased

P_M = 1e-3  # a 1 mm pitch: frequencies in cy/mm are in cycles per array pixel


def test_reciprocal_lattice_of_the_quincunx():
    k = alias_offsets_cy_per_mm(P_M, order=2)
    # every alias k satisfies exp(2 pi i k . r) = 1 on every lattice point r = i (p, 0) + j (p/2, p/2)
    r = np.array([[i * 1.0 + j * 0.5, j * 0.5] for i in range(-3, 4) for j in range(-3, 4)])  # mm
    assert np.allclose(np.cos(2 * np.pi * r @ k.T), 1.0)
    # and the lattice of the p/2 grid's other half is not a period: (1/p, 0) is not an alias
    assert not any(np.allclose(kk, [1.0, 0.0]) for kk in k)
    assert np.hypot(*k[0]) == pytest.approx(math.sqrt(2))  # the nearest copies at (+-1/p, +-1/p)
    assert nyquist_cy_per_mm(P_M) == pytest.approx(1.0)  # twice a single array's 1/(2p)
    assert nyquist_cy_per_mm(P_M, direction="diagonal") == pytest.approx(1 / math.sqrt(2))
    assert unaliased(0.99, 0.0, pitch_m=P_M) and not unaliased(0.6, 0.6, pitch_m=P_M)


@given(fx=st.floats(-0.95, 0.95), fy=st.floats(-0.95, 0.95))
@settings(max_examples=40, deadline=None)
def test_combination_transfer_function_on_sinusoids(fx, fy):
    assume(abs(fx) + abs(fy) > 0.05)  # the fit's sine column vanishes at f = 0
    """A sinusoid inside the unaliased diamond, sampled by both arrays and combined, comes out as the same
    sinusoid scaled by the combination's transfer function (the fitted amplitude, on the interior)."""
    if abs(fx) + abs(fy) > 0.95:
        fx, fy = fx / 2, fy / 2
    n = 64
    y, x = np.mgrid[0:n, 0:n] * 0.5  # the p/2 grid, in mm (= array pixels)
    img = np.cos(2 * np.pi * (fx * x + fy * y))
    out = combine_staggered(*staggered_samples(img))
    inner = (slice(2, -2), slice(2, -2))
    basis = np.stack([np.cos(2 * np.pi * (fx * x + fy * y))[inner].ravel(),
                      np.sin(2 * np.pi * (fx * x + fy * y))[inner].ravel()], 1)  # fmt: skip
    alias = np.cos(np.pi * (x + y) * 2)[inner].ravel()[:, None] * basis  # the (1/p, 1/p) copy
    coef, *_ = np.linalg.lstsq(np.hstack([basis, alias]), out[inner].ravel(), rcond=None)
    assert coef[0] == pytest.approx(float(combination_otf(fx, fy, pitch_m=P_M)), abs=1e-9)
    assert abs(coef[1]) < 1e-9


def test_combine_keeps_the_samples_and_handles_the_border():
    rng = np.random.default_rng(3)
    a, b = rng.random((5, 7)), rng.random((5, 7))
    out = combine_staggered(a, b)
    assert out.shape == (10, 14)
    assert np.array_equal(out[0::2, 0::2], a) and np.array_equal(out[1::2, 1::2], b)
    assert out[0, 1] == pytest.approx((a[0, 0] + a[0, 1] + b[0, 0]) / 3)  # the border: the neighbours inside
    assert out[2, 3] == pytest.approx((a[1, 1] + a[1, 2] + b[0, 1] + b[1, 1]) / 4)
    with pytest.raises(ValueError, match="same 2-D shape"):
        combine_staggered(a, b[:4])
    with pytest.raises(ValueError, match="method = 'cubic'"):
        combine_staggered(a, b, method="cubic")


def _edge_image(n: int, angle_deg: float, sigma_mm: float, sub: int = 12) -> np.ndarray:
    """An edge through the centre at ``angle_deg`` from the columns, blurred by a Gaussian of ``sigma_mm``, each
    sample the mean over a p-wide (1 mm) pixel centred on its point of the p/2 grid (sub x sub points)."""
    t = math.radians(angle_deg)
    nx, ny = math.cos(t), -math.sin(t)  # the edge normal (mostly x: the edge runs along the columns)
    c = (n - 1) * 0.25
    u = (np.arange(sub) + 0.5) / sub - 0.5
    y, x = np.mgrid[0:n, 0:n] * 0.5
    acc = np.zeros((n, n))
    for du in u:
        for dv in u:
            d = (x + du - c) * nx + (y + dv - c) * ny
            acc += ndtr(d / sigma_mm)
    return 0.1 + 0.5 * acc / sub**2


@pytest.mark.parametrize("angle", [4.0, 7.5])
def test_measured_mtf_beyond_a_single_arrays_nyquist_matches_the_prediction(angle):
    sigma = 0.25  # mm: a Gaussian optics blur
    img = _edge_image(128, angle, sigma)
    combined = combine_staggered(*staggered_samples(img))
    r = measure_edge(combined[8:-8, 8:-8], pitch_m=P_M / 2)
    t = math.radians(angle)
    for f_px in (0.15, 0.25, 0.35, 0.45):  # cy per combined pixel: 0.25 = the single array's Nyquist
        f = f_px * 2.0  # cy/mm (per array pixel)
        fx, fy = f * math.cos(t), f * math.sin(t)
        predicted = (math.exp(-2 * (math.pi * sigma * f) ** 2) * abs(np.sinc(fx) * np.sinc(fy))
                     * float(combination_otf(fx, fy, pitch_m=P_M)))  # fmt: skip
        measured = float(np.interp(f_px, r.f_cy_per_px, r.mtf))
        assert measured == pytest.approx(predicted, abs=0.02), (f_px, measured, predicted)
    # one array alone, at its own pitch, cannot go past 0.5 cy/px of its grid (= 0.25 here)
    a, _ = staggered_samples(img)
    single = measure_edge(a[4:-4, 4:-4], pitch_m=P_M)
    assert single.f_cy_per_px[-1] <= 1.0 + 1e-9


def _bars(n: int, period_mm: float, sigma_mm: float, sub: int = 12) -> np.ndarray:
    """Bars along the rows (reflectance 0.1 / 0.6, ``period_mm``) blurred by a Gaussian and integrated over each
    p-wide pixel centred on its point of the p/2 grid; exact: the blurred square wave as a sum of edges."""
    u = (np.arange(sub) + 0.5) / sub - 0.5
    x = np.arange(n) * 0.5
    acc = np.zeros(n)
    for du in u:
        xx = x + du
        k = np.arange(-2, int(xx.max() / period_mm) + 3)
        rises, falls = k * period_mm, k * period_mm + period_mm / 2
        acc += (ndtr((xx[:, None] - rises) / sigma_mm) - ndtr((xx[:, None] - falls) / sigma_mm)).sum(1)
    row = 0.1 + 0.5 * acc / sub
    return np.tile(row, (n, 1))


def test_bars_above_a_single_arrays_nyquist_resolved_as_predicted():
    """Bars of period 1.4 p (0.71 cy per array pixel, above one array's 0.5): the combined image holds them at
    their own frequency with the predicted amplitude; one array alone cannot tell them from bars at the alias 0.29."""
    period, sigma, f = 1.4, 0.2, 1 / 1.4
    img = _bars(160, period, sigma)
    combined = combine_staggered(*staggered_samples(img))
    x = np.arange(combined.shape[1]) * 0.5

    def amplitude(profile, xs, freq):
        basis = np.stack([np.cos(2 * np.pi * freq * xs), np.sin(2 * np.pi * freq * xs), np.ones_like(xs)], 1)
        c, *_ = np.linalg.lstsq(basis, profile, rcond=None)
        return float(np.hypot(c[0], c[1]))

    inner = slice(10, -10)
    # the quincunx's alias copies of (f, 0) sit at (f -+ 1, +-1) cy/mm: a checkerboard along y (rows alternate)
    # that an even number of rows averages out, as a bar measurement across the bars' length does
    profile = combined[20:140].mean(0)[inner]
    measured = amplitude(profile, x[inner], f)
    fundamental = 4 / np.pi * 0.25  # a square wave of peak-to-peak 0.5: its first harmonic's amplitude
    predicted = fundamental * math.exp(-2 * (math.pi * sigma * f) ** 2) * np.sinc(f) * float(
        combination_otf(f, 0.0, pitch_m=P_M)
    )
    assert predicted > 0.02
    assert measured == pytest.approx(predicted, rel=0.1, abs=0.005)
    a, _ = staggered_samples(img)
    xa = np.arange(a.shape[1]) * 1.0
    row = a[20, 5:-5]
    at_true, at_alias = amplitude(row, xa[5:-5], f), amplitude(row, xa[5:-5], 1 - f)
    assert at_true == pytest.approx(at_alias, rel=1e-9)  # one array: 0.71 and its alias 0.29 are the same samples
    assert amplitude(profile, x[inner], 1 - f) < 0.05 * measured  # combined: the bars at their own frequency
