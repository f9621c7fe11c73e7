"""Issue 29, item 12: a pushbroom run predicts a bar group's CTF by measuring a noise-free image of the target
formed where the image geometry puts each row (:mod:`satchain.prediction.bars`).

Checked against the independent exact bar renderer (:mod:`_render`: the ESF of a Gaussian x pixel system by
quadrature, exact at pixel centres), with rows displaced by known sub-pixel amounts as a slow line-of-sight
motion displaces them."""

from __future__ import annotations

import numpy as np
from _render import _GAUSS_CUT, bar_esf, bar_mtf
from affine import Affine

from satchain.measure.bars import measure_bars
from satchain.prediction.bars import predict_bar_ctf, target_model_image
from satchain.prediction.image_geometry import ImageGeometry

SIGMA = 0.45  # Gaussian blur, px
DARK, BRIGHT = 0.05, 0.8
PERIODS = (6.0, 4.0, 3.06)  # px (1 m ground pixels); the last as the ACT group 3


def _mtf(f):
    return bar_mtf(f, q=0.0, eps=0.0, blur_sigma_px=SIGMA)


_mtf.cutoff = _GAUSS_CUT / SIGMA


def _target():
    """Three groups of three long bars (x ACT), each on a dark plate as wide as the scene (no plate edges)."""
    groups, x = [], 20.3
    for p in PERIODS:
        bars = [[x + k * p, -500.0, x + k * p + p / 2, 500.0] for k in range(3)]
        groups.append({"period_m": p, "bbox_m": [-500.0, -500.0, 500.0, 500.0], "bars_m": bars})
        x += 4 * p + 6.0
    return {"id": "b", "kind": "bar_target", "dark": DARK, "bright": BRIGHT, "n_bars": 3, "groups": groups}


def _exact(target, shape, dx):
    """Row i, column j sees the ground at x = j + dx_i: the exact image of the bars (independent renderer)."""
    esf = bar_esf(0.0, 0.0, SIGMA, d_max=128.0)
    x = np.arange(shape[1], dtype=float)[None, :] + dx[:, None]
    img = np.full(shape, DARK)
    for g in target["groups"]:
        for x0, _, x1, _ in g["bars_m"]:
            img += (BRIGHT - DARK) * (esf(x - x0) - esf(x - x1))
    return img


def test_the_model_image_is_the_exact_image_where_the_rows_put_the_bars():
    rows, shape = 12, (12, 80)
    dx = 0.67 * np.sin(np.arange(rows) / 5.0)  # sub-pixel row displacements
    geo = ImageGeometry(Affine.identity(), (0.0, 0.0), dx, np.zeros(rows), {}, None, {"b": _target()}, DARK)
    rois = [(20, 2, 75, 10)]
    model = target_model_image(geo, _target(), rois, {"ACT": _mtf, "ALT": _mtf}, DARK)
    np.testing.assert_allclose(model[:, :75], _exact(_target(), shape, dx)[:, :75], atol=2e-3)


def test_the_predicted_ctf_is_the_measurement_of_the_exact_image():
    """The same estimator on the exact image and on the model: equal CTFs at every group, rows displaced (the
    3.06 px group's CTF differs from the straight rows' one: the displacements average over the rows)."""
    rows, shape = 10, (10, 96)
    target = _target()
    geo = ImageGeometry(Affine.identity(), (0.0, 0.0), np.zeros(rows), np.zeros(rows), {}, None, {"b": target}, DARK)
    dx = np.linspace(-0.6, 0.6, rows)
    moved = ImageGeometry(Affine.identity(), (0.0, 0.0), dx, np.zeros(rows), {}, None, {"b": target}, DARK)
    rois, x = [], 20.3
    for p in PERIODS:
        rois.append((int(np.ceil(x + p / 4)), 2, int(np.floor(x + 2 * p + p / 4)) + 1, 8))
        x += 4 * p + 6.0
    groups = [
        {"group": k, "period_px": p, "roi_px": list(r)} for k, (p, r) in enumerate(zip(PERIODS, rois, strict=True))
    ]
    entry = {"id": "b", "direction": "ACT", "levels_from": "truth", "groups": groups}
    for g, d in ((geo, np.zeros(rows)), (moved, dx)):
        got = predict_bar_ctf(g, entry, {"ACT": _mtf, "ALT": _mtf}, DARK)
        want = measure_bars(_exact(target, shape, d), periods_px=list(PERIODS), group_rois=rois,
                            levels=(DARK, BRIGHT), bars_per_group=3).ctf  # fmt: skip
        np.testing.assert_allclose(got, np.asarray(want, float), atol=3e-3)
    straight = predict_bar_ctf(geo, entry, {"ACT": _mtf, "ALT": _mtf}, DARK)
    assert straight[2] - predict_bar_ctf(moved, entry, {"ACT": _mtf, "ALT": _mtf}, DARK)[2] > 0.02
