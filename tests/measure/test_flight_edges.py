"""Measurement on flight images (issue 19): a Baotou-like crop with an area-of-interest mask of zeros.

The image is rendered exactly by tests/measure/_render_baotou.py (a known, non-Gaussian MTF: a sharp core
with a halo, and the pixel aperture).
"""

from __future__ import annotations

import numpy as np
import pytest
from _render_baotou import render_baotou, truth_mtf
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from satchain.errors import InputError
from satchain.measure._clipping import find_clipping
from satchain.measure._common import zero_fill_mask
from satchain.measure.edge import measure_edge
from satchain.measure.find import estimate_noise, find_edges
from satchain.measure.find_mtf import measure_found_edges


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    angle=st.floats(10.0, 20.0),
    phase=st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5)),
    seed=st.integers(0, 2**16),
)
def test_find_on_baotou_crop_with_defaults(angle, phase, seed):
    img, valid = render_baotou(angle_deg=angle, phase=phase, seed=seed, sub=8)
    res = measure_found_edges(img, nodata=0)
    assert len(res.edges) == 4  # the four halves of the cross, each >= 25 px
    assert all(e.candidate.length_px >= 25 for e in res.edges)
    assert sorted(e.direction for e in res.edges) == ["ACT", "ACT", "ALT", "ALT"]
    for e in res.edges:
        assert e.joined_with is not None  # collinear halves joined
        true = -angle if e.direction == "ACT" else 90.0 - angle
        assert abs(e.angle_deg - true) < 0.2
    truth = truth_mtf(0.5, angle)
    for d in ("ACT", "ALT"):
        c = res.combined[d]
        # unbiased within its noise (1 sigma ~0.008, more where the Birge ratio inflates it after two edges
        # disagree by chance; 30 renders: rms error 0.008, max 0.017 -- benchmarks/bench_flight_baotou.py)
        assert c.mtf_at_nyquist_sigma < 0.025
        assert abs(c.mtf_at_nyquist - truth) < 4 * c.mtf_at_nyquist_sigma
    # the noise is that of the target (40-66 DN), not pulled down by the zeros
    assert 38.0 < res.noise_sigma < 66.0


def test_zeros_outside_the_aoi_are_not_clipping():
    img, valid = render_baotou(seed=1, sub=8)
    roi = (35, 5, 70, 42)  # the upper half of the near-vertical edge, with the AOI border in it
    with pytest.raises(InputError, match="clipped"):  # float zeros: no evidence they are a fill
        measure_edge(img.astype(float), roi=roi)
    for kw in ({"nodata": 0}, {"valid": valid}, {}):
        r = measure_edge(img, roi=roi, **kw)
        assert r.direction == "ACT" and "clipping" not in r.flags
        assert ("nodata_fill" in r.flags) == (not kw)  # uint16 zeros far below the data: a fill, flagged
        assert 40.0 < r.noise_sigma < 66.0
        assert abs(r.mtf_at_nyquist - truth_mtf(0.5, 16.8)) < 3 * r.mtf_at_nyquist_sigma + 0.02


def test_noise_estimates_ignore_excluded_pixels():
    img, valid = render_baotou(seed=2, sub=8)
    assert estimate_noise(img) < 35.0  # the zeros pull it down ...
    assert 40.0 < estimate_noise(img, valid=valid) < 66.0  # ... not when they are excluded
    assert find_clipping(img, valid=valid) is None


def test_noise_free_edge_in_a_small_region_is_not_clipped():
    img, valid = render_baotou(seed=None, sub=8)
    r = measure_edge(img, roi=(40, 10, 64, 40), valid=valid)
    assert "clipping" not in r.flags
    assert abs(r.mtf_at_nyquist - truth_mtf(0.5, 16.8)) < 0.03


def test_zero_fill_taken_as_nodata_only_on_evidence():
    img, valid = render_baotou(seed=6, sub=8)
    res = measure_found_edges(img)  # defaults: the uint16 zero fill is found and excluded
    assert any("taken as nodata" in f for f in res.flags)
    assert 38.0 < res.noise_sigma < 66.0
    mask, note = zero_fill_mask(img)
    assert note and np.array_equal(mask, valid)
    # a dark plateau clipped at 0 (values reach 0 smoothly) and a float image are data, not a fill
    ramp = np.clip(np.round(np.linspace(-200, 3000, 80)[None, :] + np.zeros((80, 1))), 0, None).astype(np.uint16)
    assert zero_fill_mask(ramp) == (None, None)
    assert zero_fill_mask(img.astype(float)) == (None, None)


def test_mask_border_is_no_edge():
    img, valid = render_baotou(seed=4, sub=8)
    s = find_edges(img, valid=valid)
    assert len(s) == 4
    assert not [r for r in s.rejected if r.length_px > 60]  # the AOI border is never a segment


def test_bad_masks_are_refused():
    img, valid = render_baotou(seed=5, sub=8)
    with pytest.raises(InputError, match="valid"):
        measure_edge(img, valid=valid[:-1])
    with pytest.raises(InputError, match="every pixel is excluded"):
        measure_found_edges(np.zeros((64, 64), np.uint16), nodata=0)


def test_joined_halves_are_measured_on_the_joint_line():
    """Each joined half's ESF is projected on the joint line (twice the baseline): on an exact, noise-free render
    its angle is right to 0.01 deg (its own fit is 0.03-0.08 deg off) and its MTF at Nyquist is at least as close
    to the truth as on its own line (benchmarks/bench_flight_baotou.py --no-noise: rms 0.0056 both ways)."""
    angle = 16.8
    img, valid = render_baotou(angle_deg=angle, seed=None, sub=8)
    res = measure_found_edges(img, valid=valid)
    truth = truth_mtf(0.5, angle)
    assert len(res.edges) == 4
    for e, r in zip(res.edges, res.results, strict=True):
        true = -angle if e.direction == "ACT" else 90.0 - angle
        assert e.joined_with is not None and e.own_mtf_at_nyquist is not None
        assert abs(r.angle_deg - true) < 0.01 and r.angle_deg == pytest.approx(e.angle_deg)  # the joint line used
        assert abs(e.angle_deg - true) <= abs(e.own_angle_deg - true)
        assert abs(e.mtf_at_nyquist - truth) <= abs(e.own_mtf_at_nyquist - truth) + 1e-3
        assert abs(e.mtf_at_nyquist - truth) < 0.012


def test_a_wrong_edge_line_lowers_the_mtf():
    """``edge_line``: the ESF follows the line given; a line tilted off the edge smears the ESF (lower MTF)."""
    angle = 16.8
    img, valid = render_baotou(angle_deg=angle, seed=None, sub=8)
    roi = (27, 54, 62, 85)  # the lower half of the near-vertical edge (ACT)
    c = (img.shape[0] - 1) / 2  # the target centre lies on the edge line
    mtf = []
    for off in (0.0, 0.5, 1.0):
        r = measure_edge(img, roi=roi, valid=valid, edge_line=(c, c, -angle + off))
        assert r.angle_deg == pytest.approx(-angle + off)
        mtf.append(r.mtf_at_nyquist)
    assert abs(mtf[0] - truth_mtf(0.5, angle)) < 0.01
    assert mtf[0] > mtf[1] > mtf[2]
    with pytest.raises(InputError, match="edge_line"):
        measure_edge(img, roi=roi, valid=valid, edge_line=(c, c, 80.0))  # not this region's ACT edge
