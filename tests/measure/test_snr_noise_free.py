"""measure_snr on a noise-free image (issue 29, item 7): the background's scatter there is the scene's own structure
(the optics' tails around the targets), not noise, and gave an SNR of thousands with no word. It is named
(``noise_free``, SNR NaN with the reason) when neighbouring pixels' differences are correlated, as smooth structure
makes them, and not for white noise at SNR 50 or 500. The images are rendered here: a reflectance scene with two
edges, blurred and sampled by the reference camera, white noise drawn on top."""

from __future__ import annotations

import math

import numpy as np
import pytest

import satchain
from satchain.measure.snr import GIQE_CONTRAST, measure_snr

GSD_M = 0.49  # ankarasat3
FINE_M = GSD_M / 5
BACKGROUND = 0.2


def _edge_item(x0, y0, size, vertical):
    return {"kind": "slanted_edge", "id": f"e{x0}_{y0}", "bbox_m": [x0, y0, x0 + size, y0 + size],
            "edge_point_m": [x0 + size / 2, y0 + size / 2], "normal_to_bright": [1.0, 0.0] if vertical else [0.0, 1.0],
            "bright": 0.7, "dark": 0.1}  # fmt: skip


ITEMS = [_edge_item(5.0, 5.0, 20.0, True), _edge_item(40.0, 5.0, 20.0, False)]
TRUTH = {"items": ITEMS, "background": BACKGROUND}


@pytest.fixture(scope="module")
def noise_free() -> np.ndarray:
    """The scene (background 0.2, two 20 m squares split by an edge) at 0.098 m, imaged without noise (160 x 160)."""
    n = 800
    refl = np.full((n, n), BACKGROUND)
    yy, xx = (np.mgrid[0:n, 0:n] + 0.5) * FINE_M
    for it in ITEMS:
        x0, y0, x1, y1 = it["bbox_m"]
        inside = (xx >= x0) & (xx < x1) & (yy >= y0) & (yy < y1)
        d = (xx - it["edge_point_m"][0]) * it["normal_to_bright"][0] + (yy - it["edge_point_m"][1]) * it[
            "normal_to_bright"
        ][1]
        refl[inside] = np.where(d[inside] >= 0, it["bright"], it["dark"])
    return satchain.simulate(refl, satchain.load_preset("ankarasat3"), pixel_m=FINE_M)  # reflectance, no noise


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_noise_free_image_is_named_not_given_an_snr(noise_free, dtype):
    r = measure_snr(noise_free.astype(dtype), TRUTH, pixel_m=GSD_M)
    assert "noise_free" in r.flags
    assert math.isnan(r.snr) and r.snr_sigma is None
    assert "noise-free" in r.reason
    # float64: the scatter is the optics' tails (correlated); float32 rounds the flat background below that
    assert ("correlated" if dtype == np.float64 else "resolution") in r.reason
    assert r.to_dict()["flags"] == ["noise_free"]


@pytest.mark.parametrize("snr", [50.0, 500.0])
def test_white_noise_is_measured_and_not_flagged(noise_free, snr):
    sigma = 1.0 * GIQE_CONTRAST / snr  # gain 1: reflectance units
    rng = np.random.default_rng(7)
    r = measure_snr(noise_free + rng.normal(0.0, sigma, noise_free.shape), TRUTH, pixel_m=GSD_M)
    assert r.flags == () and r.reason is None
    # measured within 30 % (the plateaus' rows also carry some of the edges' blur at SNR 500)
    assert r.snr == pytest.approx(snr, rel=0.3)


def test_an_image_whose_scatter_is_below_its_float_resolution_is_named():
    """A flat background carrying only rounding-sized scatter (1e-15 of the level) is no measurement of noise."""
    rng = np.random.default_rng(3)
    img = np.full((160, 160), BACKGROUND)
    yy, xx = (np.mgrid[0:160, 0:160] + 0.5) * GSD_M
    for it in ITEMS:
        x0, y0, x1, y1 = it["bbox_m"]
        inside = (xx >= x0) & (xx < x1) & (yy >= y0) & (yy < y1)
        d = (xx - it["edge_point_m"][0]) * it["normal_to_bright"][0] + (yy - it["edge_point_m"][1]) * it[
            "normal_to_bright"
        ][1]
        img[inside] = np.where(d[inside] >= 0, 0.7, 0.1)
    img = img * (1 + rng.normal(0.0, 1e-15, img.shape))  # a few float64 roundings: white, but no noise
    r = measure_snr(img, TRUTH, pixel_m=GSD_M)
    assert "noise_free" in r.flags and math.isnan(r.snr) and "resolution" in r.reason
