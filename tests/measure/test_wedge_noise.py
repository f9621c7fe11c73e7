"""Wedge noise estimate and crossing 1-sigma (issue 18) on exact converging-line renders (_render_wedge.py).

The noise estimate must not read sharp converging stripes as noise (a noise-free wedge gives ~0 and is
measured, not refused) and must be within ~20 % of the true sigma from low to high noise, sharp or blurred.
The crossing's 1-sigma must match the scatter of the crossing over noise realisations, and the noise-free
crossing must lie within 2 sigma in most of them (the max-min contrast's noise bias removed).
"""

from __future__ import annotations

import numpy as np
import pytest
from _render_wedge import hyperbolic, linear, render_wedge, widths_at_columns
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain.measure.wedge import measure_wedge

HYP = hyperbolic(4.0, 30.0)  # 3.9 -> 0.63 px over 160 columns
LIN = linear(3.0, 0.015)  # 3.0 -> 0.6 px


@settings(max_examples=10, deadline=None)
@given(
    shape=st.sampled_from(["hyperbolic", "linear"]),
    blur=st.sampled_from([0.0, 0.0, 0.3, 0.6, 1.0]),
    phase=st.floats(0.0, 1.0),
)
def test_noise_free_wedge_reads_no_noise_and_is_measured(shape, blur, phase):
    """Sharp converging lines put most pixels on a moving stripe boundary; the old estimate read them as
    noise of 0.4-1.6 % of the stripe contrast and refused the sharpest wedges ("not above the noise")."""
    width = HYP if shape == "hyperbolic" else LIN
    img = render_wedge(width, rows=40, cols=120, blur=blur, phase=phase)
    r = measure_wedge(img, line_width_px=widths_at_columns(width, 120))
    assert r.noise_std < 2e-3 * 0.6
    assert r.contrast[0] > 0.3


@settings(max_examples=8, deadline=None)
@given(
    shape=st.sampled_from(["hyperbolic", "linear"]),
    blur=st.sampled_from([0.0, 0.3, 0.6, 1.0]),
    phase=st.floats(0.0, 1.0),
    sigma=st.sampled_from([0.002, 0.01, 0.05]),
    seed=st.integers(0, 1000),
)
def test_noise_estimate_is_unbiased_on_wedge_images(shape, blur, phase, sigma, seed):
    """Mean of the estimate over 3 realisations within 35 % of sigma (the worst cases, sharp lines at a stripe
    contrast-to-noise of 12 and a blurred (0.6 px) linear wedge at 300, read up to 1.31: the pattern's residue
    leaks in when the noise is tiny, an over-estimate; the old estimate read 2-8)."""
    width = HYP if shape == "hyperbolic" else LIN
    img = render_wedge(width, rows=48, cols=160, blur=blur, phase=phase)
    lw = widths_at_columns(width, 160)
    est = []
    for k in range(3):
        noisy = img + np.random.default_rng(seed + k).normal(0, sigma, img.shape)
        try:
            est.append(measure_wedge(noisy, line_width_px=lw).noise_std)
        except ValueError as exc:  # a refusal may only name the noise, at a stripe contrast-to-noise of 12
            assert sigma == 0.05 and "no wedge" in str(exc)
    if est:
        assert np.mean(est) == pytest.approx(sigma, rel=0.35)


def test_noise_estimate_ignores_the_fill_outside_valid():
    """The run fills rows outside the stripes with each column's median: ``valid`` keeps them out."""
    width = LIN
    img = render_wedge(width, rows=48, cols=160, blur=0.6, phase=0.3)
    noisy = img + np.random.default_rng(1).normal(0, 0.01, img.shape)
    valid = np.ones(img.shape, bool)
    valid[30:, 60:] = False
    noisy[~valid] = np.broadcast_to(np.median(noisy[:30], axis=0), img.shape)[~valid]
    lw = widths_at_columns(width, 160)
    assert measure_wedge(noisy, line_width_px=lw, valid=valid).noise_std == pytest.approx(0.01, rel=0.15)
    with pytest.raises(ValueError, match="valid"):
        measure_wedge(noisy, line_width_px=lw, valid=valid[:, :10])


@pytest.mark.parametrize(
    ("width", "blur", "sigma"),
    [(HYP, 1.0, 0.002), (HYP, 1.0, 0.006), (LIN, 0.7, 0.002), (LIN, 0.7, 0.006)],
    ids=["hyperbolic-low", "hyperbolic-high", "linear-low", "linear-high"],
)
def test_crossing_sigma_matches_the_scatter(width, blur, sigma):
    """Over 30 noise realisations: scatter of the crossing / mean reported 1-sigma in [0.6, 1.6], and the
    noise-free crossing within 2 sigma in >= 85 % (the old 1-sigma was 3-10x the scatter here)."""
    img = render_wedge(width, rows=48, cols=160, blur=blur, phase=0.21)
    lw = widths_at_columns(width, 160)
    ref = measure_wedge(img, line_width_px=lw)
    vals, sds = [], []
    for seed in range(30):
        r = measure_wedge(img + np.random.default_rng(seed).normal(0, sigma, img.shape), line_width_px=lw)
        vals.append(r.resolved_line_width_px)
        sds.append(r.resolved_line_width_px_std)
    vals, sds = np.array(vals), np.array(sds)
    assert 0.6 <= np.std(vals, ddof=1) / np.mean(sds) <= 1.6
    assert np.mean(np.abs(vals - ref.resolved_line_width_px) < 2 * sds) >= 0.85


def test_sampling_wobble_is_reported_apart_from_noise():
    """A noise-free wedge has no noise 1-sigma; the wobble of its contrast curve near the crossing (sampling
    phase) is a separate, deterministic figure."""
    img = render_wedge(LIN, rows=48, cols=160, blur=0.0, phase=0.21)  # noise estimate exactly 0
    r = measure_wedge(img, line_width_px=widths_at_columns(HYP, 160))
    assert r.noise_std < 1e-4 and r.resolved_line_width_px_std < 0.01 * r.resolved_line_width_px_sampling_std
