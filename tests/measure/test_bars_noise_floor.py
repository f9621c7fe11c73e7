"""Issue 29, item 15: a bar group whose modulation is at the noise floor is a result (CTF ~0 with its 1-sigma,
flagged ``at_noise_floor``), not a refusal; what cannot be measured is still refused.

Groups rendered exactly (Gaussian PSF x pixel box, exact CDF at pixel centres; test_bars._group), then smeared by a
3 px box along the profile (the mean of 48 evenly spaced shifts: the midpoint rule of the box integral). A 3 px
period sits at the smear's sinc null: sinc(3 k / 3) = 0 for every odd harmonic k, so Coltman's CTF there is exactly 0.
"""

from __future__ import annotations

import math

import numpy as np
from test_bars import _box_gauss_cdf, _group

from satchain.measure.bars import measure_bars

S = 0.5  # Gaussian sigma (px)
SMEAR_PX = 3.0
PERIODS = (12.0, 6.0, 4.0, 3.0)


def _smeared_group(period, phase, rows=8, dark=40.0, bright=160.0):
    """test_bars._group's 3-bar group and region, smeared by SMEAR_PX along the profile."""
    start = 3 * period + phase
    x = np.arange(int(math.ceil(start + 6 * period)), dtype=float)
    v = np.full(x.size, dark)
    for u in (np.arange(48) + 0.5) / 48 * SMEAR_PX - SMEAR_PX / 2:
        for k in range(3):
            u0 = start + k * period + u
            v += (bright - dark) / 48 * (_box_gauss_cdf(x - u0, S) - _box_gauss_cdf(x - u0 - period / 2, S))
    return np.tile(v, (rows, 1)), _group(period, phase, 3, S, rows=rows)[1]


def _target(groups, rows=8):
    blocks, rois, x0 = [], [], 0
    for img, roi in groups:
        blocks.append(img)
        rois.append((roi[0] + x0, 0, roi[2] + x0, rows))
        x0 += img.shape[1]
    return np.hstack(blocks), rois


def test_a_group_at_the_smears_sinc_null_is_measured_at_the_noise_floor():
    """The 3 px group under a 3 px smear (true CTF 0): measured, CTF within 3 sigma (+ the Rayleigh bias of a
    free-phase amplitude, < 1.3 sigma) of 0, flagged at_noise_floor under its own index; nothing refused."""
    rng = np.random.default_rng(29)
    img, rois = _target([_smeared_group(p, 0.3) for p in PERIODS])
    img = img + rng.normal(0.0, 0.5, img.shape)
    r = measure_bars(img, periods_px=PERIODS, group_rois=rois, levels=(40.0, 160.0))
    assert r.refused == ()
    ctf, std = float(r.ctf[3]), float(r.ctf_std[3])
    assert np.isfinite(ctf) and 0 < std < 0.05
    assert abs(ctf) <= 4.3 * std
    assert any(f.startswith("group 3: at_noise_floor") for f in r.flags)
    assert not any(f.startswith(("group 0: at_noise", "group 1: at_noise", "group 2: at_noise")) for f in r.flags)
    assert np.all(r.ctf[:3] > 0.1)  # the wider groups stand well above the noise


def test_a_flat_region_is_ctf_zero_not_a_refusal_and_indices_stay():
    """A flat noisy region where the 6 px group is claimed: modulation at the noise floor (CTF ~0 +- sigma),
    measured under index 1; the other groups keep their own indices."""
    rng = np.random.default_rng(3)
    img, rois = _target([_group(p, 0.3, 3, S) for p in (12.0, 6.0, 4.0, 3.0, 2.5)])
    x0, _, x1, _ = rois[1]
    img[:, x0 - 2 : x1 + 2] = 100.0 + rng.normal(0.0, 1.0, (img.shape[0], x1 - x0 + 4))
    r = measure_bars(img, periods_px=(12.0, 6.0, 4.0, 3.0, 2.5), group_rois=rois, levels=(40.0, 160.0))
    assert r.refused == ()
    assert abs(r.ctf[1]) <= 4.3 * r.ctf_std[1] and r.ctf_std[1] > 0
    assert [f.split(":")[0] for f in r.flags if "at_noise_floor" in f] == ["group 1"]


def test_a_region_holding_another_period_is_still_refused():
    """The 6 px group's region (widened to 5 periods) holds a strong 2.7 px grating: no bars at 6 px, another
    period stands out: refused alone (not a noise floor), the others measured."""
    (g0, roi0), (g2, roi2) = _group(12.0, 0.3, 3, S), _group(4.0, 0.3, 3, S)
    xx = np.arange(40.0)
    grating = np.tile(100.0 + 50.0 * np.cos(2 * np.pi * xx / 2.7), (8, 1))
    img, rois = _target([(g0, roi0), (grating, (5, 0, 35, 8)), (g2, roi2)])
    r = measure_bars(img, periods_px=(12.0, 6.0, 4.0), group_rois=rois, levels=(40.0, 160.0))
    assert [i for i, _ in r.refused] == [1]
    assert not any("at_noise_floor" in f for f in r.flags)


def test_measure_auto_names_a_refusal_by_the_groups_design_number():
    """measure_bars numbers the groups it is given; measure auto gives it the design's groups from the first one
    inside Nyquist: a refusal's ``group_rois[j]`` / ``periods_px[j]`` is renamed to the design's index."""
    from satchain.measure.auto._items import _design

    keep = [1, 3, 4]  # group 0 beyond Nyquist, group 2 refused earlier
    msg = "group_rois[1]: no bars; periods_px[2] = 2.5: ..."
    assert _design(msg, keep) == "group_rois[3]: no bars; periods_px[4] = 2.5: ..."
