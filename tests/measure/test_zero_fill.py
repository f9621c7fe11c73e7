"""A zero fill outside the area of interest, told from a real dark area clipped at 0, with or without noise.

Fills: Baotou-like crops rendered exactly by tests/measure/_render_baotou.py (0 outside a rotated AOI).  Dark
targets: an edge, a bar and three bars with ends, each a Gaussian-blurred step integrated over the pixel and
clipped at 0 (tests/measure/_render_dark.py).  Rates over a wide sweep: benchmarks/bench_zero_fill.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from _render_baotou import GAIN_DN, READ_DN, render_baotou, truth_mtf
from _render_dark import render_dark_target
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from satchain.measure._zero_fill import _border_steps, zero_fill_evidence, zero_fill_mask
from satchain.measure.edge import measure_edge
from satchain.measure.find_mtf import measure_found_edges

SLOW = {"deadline": None, "suppress_health_check": [HealthCheck.too_slow]}


def _crop(angle, fraction, phase, noise, dtype, seed=0):
    """A Baotou-like crop as cal/val tools write it: noise-free render, scaled to ``dtype``, noise, 0 outside."""
    img, valid = render_baotou(angle_deg=angle, phase=phase, fill_fraction=fraction, seed=None, sub=4)
    scale, top = (1.0, 65535) if dtype == np.uint16 else (250.0 / 9300.0, 255)
    sig = np.sqrt(READ_DN**2 + GAIN_DN * img) * scale if noise else 0.0
    noisy = img * scale + sig * np.random.default_rng(seed).normal(size=img.shape)
    return np.where(valid, np.clip(np.round(noisy), 1, top), 0).astype(dtype), valid


@settings(max_examples=12, **SLOW)
@given(
    angle=st.floats(3.0, 45.0),
    fraction=st.floats(0.1, 0.55),
    phase=st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5)),
    noise=st.booleans(),
    dtype=st.sampled_from([np.uint16, np.uint8]),
)
def test_a_zero_fill_is_found_with_or_without_noise(angle, fraction, phase, noise, dtype):
    img, valid = _crop(angle, fraction, phase, noise, dtype)
    mask, note = zero_fill_mask(img)
    assert mask is not None and np.array_equal(mask, valid)  # exactly the pixels inside the AOI
    assert "taken as nodata" in note


@settings(max_examples=25, **SLOW)
@given(
    kind=st.sampled_from(["edge", "bar", "bars"]),
    angle=st.one_of(st.floats(0.0, 45.0), st.sampled_from([0.0, 45.0])),
    blur=st.floats(0.3, 2.0),
    depth=st.one_of(st.floats(0.0, 5.0), st.just(0.0)),
    offset=st.floats(0.0, 1.0),
    noise=st.sampled_from([0.0, 0.01, 0.03]),
    dtype=st.sampled_from([np.uint16, np.uint8]),
)
def test_a_dark_target_clipped_at_0_is_never_a_fill(kind, angle, blur, depth, offset, noise, dtype):
    """A dark level ``depth`` x the bright level below 0 (0: the blur itself goes down to 0) stays data."""
    bright = 200.0 if dtype == np.uint8 else 1000.0
    img = render_dark_target(
        kind=kind, angle_deg=angle, blur_px=blur, dark=-depth * bright, bright=bright, offset_px=offset,
        bar_px=8.0, noise=noise * bright, dtype=dtype, size=48, sub=4,
    )  # fmt: skip
    assume((img == 0).mean() > 0.02)  # a large set of zeros (a wide blur can lift a thin bar off 0)
    ev = zero_fill_evidence(img)
    assert ev is None or ev.verdict != "fill"  # None: the zeros cannot be a fill (e.g. none on the border)
    assert zero_fill_mask(img)[0] is None


def test_an_axis_aligned_clean_step_is_not_guessed():
    """A sharp edge along the pixel axes, clipped deep below 0, can jump from 0 to its plateau in one pixel,
    as a fill along the axes does: both are kept as data and flagged, never taken as nodata."""
    dark = render_dark_target(angle_deg=0.0, blur_px=0.3, dark=-5000.0, bright=1000.0, offset_px=0.2, size=48)
    img, _ = render_baotou(angle_deg=16.8, aoi_px=1e3, seed=3, sub=4)
    frame = img.copy()
    frame[:, :15], frame[:12, :] = 0, 0  # an axis-aligned AOI
    for a in (dark, frame):
        mask, note = zero_fill_mask(a)
        assert mask is None and "may be a fill" in note and "--nodata 0" in note
    r = measure_found_edges(frame)  # the axis-aligned border is no edge (tilt 0); the flag says why
    assert any("may be a fill" in f for f in r.flags)


def test_banded_border_steps_equal_the_whole_image():
    img, _ = render_baotou(seed=3, sub=4)
    whole, bands = _border_steps(img, img == 0, 512), _border_steps(img, img == 0, 7)
    for w, b in zip(whole, bands, strict=True):
        np.testing.assert_allclose(b, w, atol=1e-5)


@pytest.mark.parametrize("angle", [11.3, 16.8])
def test_find_with_defaults_on_a_noise_free_crop(angle):
    """Noise-free uint16: the fill is excluded with defaults, so its border is no edge and the MTF is right."""
    img, valid = render_baotou(angle_deg=angle, phase=(0.2, -0.3), seed=None, sub=6)
    img = np.round(img).astype(np.uint16)
    res = measure_found_edges(img)
    assert any("taken as nodata" in f for f in res.flags)
    assert len(res.edges) == 4 and all(e.joined_with is not None for e in res.edges)
    truth = truth_mtf(0.5, angle)
    for d in ("ACT", "ALT"):
        assert abs(res.combined[d].mtf_at_nyquist - truth) < 0.02
    r = measure_edge(img, roi=(35, 5, 70, 42))  # the AOI border in the region: no clipping, the fill flagged
    assert "nodata_fill" in r.flags and "clipping" not in r.flags
    assert abs(r.mtf_at_nyquist - truth_mtf(0.5, angle)) < 0.03
