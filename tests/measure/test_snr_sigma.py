"""The measured SNR's own 1-sigma (``snr_sigma``): over noise seeds it matches the scatter of the SNR and covers
the true SNR, on images rendered here (known gain, offset, read and shot noise, optionally rounded to DN)."""

import math

import numpy as np
import pytest

from satchain.measure.snr import GIQE_CONTRAST, GIQE_REFLECTANCE, MIN_SIGMA_PATCHES, measure_snr

PIXEL_M = 0.5
BACKGROUND = 0.2
SEEDS = range(30)


def edge_item(x0, y0, size, vertical, bright=0.7, dark=0.1):
    return {"kind": "slanted_edge", "id": f"e{x0}_{y0}", "bbox_m": [x0, y0, x0 + size, y0 + size],
            "edge_point_m": [x0 + size / 2, y0 + size / 2], "normal_to_bright": [1.0, 0.0] if vertical else [0.0, 1.0],
            "bright": bright, "dark": dark}  # fmt: skip


ITEMS = [edge_item(5.0, 5.0, 20.0, True), edge_item(40.0, 5.0, 20.0, False)]


def reflectance(shape=(160, 160)):
    """Background 0.2 with a vertical and a horizontal edge, each pixel wholly on one side (pixel centres)."""
    refl = np.full(shape, BACKGROUND)
    yy, xx = (np.mgrid[0 : shape[0], 0 : shape[1]] + 0.5) * PIXEL_M
    for it in ITEMS:
        x0, y0, x1, y1 = it["bbox_m"]
        inside = (xx >= x0) & (xx < x1) & (yy >= y0) & (yy < y1)
        d = (xx - it["edge_point_m"][0]) * it["normal_to_bright"][0] + (yy - it["edge_point_m"][1]) * it[
            "normal_to_bright"
        ][1]
        refl[inside] = np.where(d[inside] >= 0, it["bright"], it["dark"])
    return refl


def image(gain, offset, read, shot, seed, *, quantise=False):
    """offset + gain r + noise of variance read^2 + shot gain r; rounded to whole DN when ``quantise``."""
    refl = reflectance()
    rng = np.random.default_rng(seed)
    img = offset + gain * refl + rng.normal(0.0, 1.0, refl.shape) * np.sqrt(read**2 + shot * gain * refl)
    return np.round(img) if quantise else img


def true_snr(gain, read, shot, quantise=False):
    """GIQE contrast over the noise at reflectance 0.15 (plus 1/12 DN^2 of rounding when quantised)."""
    return gain * GIQE_CONTRAST / math.sqrt(read**2 + shot * gain * GIQE_REFLECTANCE + (1 / 12 if quantise else 0))


@pytest.mark.parametrize(
    ("gain", "offset", "read", "shot", "quantise"),
    [(1000.0, 50.0, 4.0, 0.0, False), (400.0, 20.0, 1.5, 0.5, True)],
    ids=["read-noise", "shot-noise-in-DN"],
)
def test_snr_sigma_matches_the_scatter_and_covers_the_truth(gain, offset, read, shot, quantise):
    """Over 30 seeds: std(snr) / mean(snr_sigma) in [0.6, 1.6], and |snr - truth| < 2 snr_sigma in >= 85 %."""
    results = [measure_snr(image(gain, offset, read, shot, s, quantise=quantise), {"items": ITEMS,
               "background": BACKGROUND}, pixel_m=PIXEL_M) for s in SEEDS]  # fmt: skip
    assert all(r.reason is None and r.snr_sigma_null_means is None for r in results)
    snr = np.array([r.snr for r in results])
    sig = np.array([r.snr_sigma for r in results])
    assert np.all(sig > 0)
    assert 0.6 <= np.std(snr, ddof=1) / np.mean(sig) <= 1.6
    assert np.mean(np.abs(snr - true_snr(gain, read, shot, quantise)) < 2 * sig) >= 0.85


def test_snr_sigma_is_reproducible_and_in_the_json():
    img = image(1000.0, 50.0, 4.0, 0.0, 3)
    truth = {"items": ITEMS, "background": BACKGROUND}
    a, b = measure_snr(img, truth, pixel_m=PIXEL_M), measure_snr(img, truth, pixel_m=PIXEL_M)
    assert a.snr_sigma == b.snr_sigma  # seeded bootstrap
    d = a.to_dict()
    assert d["snr_sigma"] == pytest.approx(a.snr_sigma) and d["snr_sigma_null_means"] is None


@pytest.mark.parametrize(("scale", "offset"), [(0.25, 0.0), (8.0, -300.0), (1.0, 5000.0)])
def test_snr_and_its_sigma_do_not_depend_on_the_image_unit(scale, offset):
    """A linear change of unit (DN -> electrons, another offset) leaves the SNR and its sigma as they were."""
    truth = {"items": ITEMS, "background": BACKGROUND}
    img = image(3000.0, 100.0, 2.0, 2.0, 5)
    a, b = measure_snr(img, truth, pixel_m=PIXEL_M), measure_snr(scale * img + offset, truth, pixel_m=PIXEL_M)
    assert b.snr == pytest.approx(a.snr, rel=1e-9)
    assert b.snr_sigma == pytest.approx(a.snr_sigma, rel=1e-6)


def test_no_sigma_says_why():
    truth = {"items": ITEMS, "background": BACKGROUND}
    r = measure_snr(image(1000.0, 0.0, 2.0, 0.0, 0), {"items": []}, pixel_m=PIXEL_M)
    assert math.isnan(r.snr) and r.snr_sigma is None and "slanted edge" in r.snr_sigma_null_means
    r = measure_snr(np.full((160, 160), 300.0) + 1000.0 * (reflectance() - BACKGROUND), truth, pixel_m=PIXEL_M)
    assert math.isnan(r.snr) and r.snr_sigma is None and "noise" in r.snr_sigma_null_means
    assert r.to_dict()["snr_sigma"] is None
    # 64 x 144 px: three target-free background patches give an SNR but too few to resample for its sigma
    r = measure_snr(image(1000.0, 50.0, 4.0, 0.0, 0)[:64, :144], truth, pixel_m=PIXEL_M)
    assert math.isfinite(r.snr) and r.reason is None
    assert r.snr_sigma is None and f"at least {MIN_SIGMA_PATCHES}" in r.snr_sigma_null_means


def test_a_blurred_edge_profile_does_not_enter_the_noise():
    """Both edges blurred (Gaussian, sigma 2 px, exact erf profile at the pixel centres): 4 px out the profile
    still slopes ~3 % of the step per px, which differences across the edge would count as noise (~+5 %)."""
    from scipy.special import erf

    yy, xx = (np.mgrid[0:160, 0:160] + 0.5) * PIXEL_M
    refl = np.full(xx.shape, BACKGROUND)
    for it in ITEMS:
        x0, y0, x1, y1 = it["bbox_m"]
        inside = (xx >= x0) & (xx < x1) & (yy >= y0) & (yy < y1)
        (px, py), (nx, ny) = it["edge_point_m"], it["normal_to_bright"]
        d_px = ((xx - px) * nx + (yy - py) * ny) / PIXEL_M
        profile = it["dark"] + (it["bright"] - it["dark"]) * 0.5 * (1 + erf(d_px / (2.0 * math.sqrt(2))))
        refl[inside] = profile[inside]
    truth = {"items": ITEMS, "background": BACKGROUND}
    gain, read, shot = 4000.0, 2.0, 0.07
    sd = np.sqrt(read**2 + shot * gain * refl)
    noise = [measure_snr(gain * refl + np.random.default_rng(s).normal(0, 1, refl.shape) * sd, truth,
                         pixel_m=PIXEL_M).noise_dn for s in range(4)]  # fmt: skip
    assert np.mean(noise) == pytest.approx(math.sqrt(read**2 + shot * gain * GIQE_REFLECTANCE), rel=0.02)


def test_a_known_gain_replaces_the_plateau_gain():
    """Plateaus pulled toward their surroundings (a wide, low scatter halo: 6 % of the light spread over the
    scene) read the gain low; given the true gain (as the run passes measure_auto's tail-modelled calibration),
    the SNR is the true one within its sigma, and the plateau-only estimate is biased low."""
    from scipy.ndimage import uniform_filter

    gain, read = 1000.0, 4.0
    refl = reflectance()
    halo = 0.94 * refl + 0.06 * uniform_filter(refl, size=61, mode="reflect")
    truth = {"items": ITEMS, "background": BACKGROUND}
    rng = np.random.default_rng(7)
    img = 50.0 + gain * halo + rng.normal(0.0, read, refl.shape)
    plain = measure_snr(img, truth, pixel_m=PIXEL_M)
    given = measure_snr(img, truth, pixel_m=PIXEL_M, gain=gain)
    expected = true_snr(gain, read, 0.0)
    assert given.gain_dn_per_reflectance == gain
    assert abs(given.snr - expected) < 2.5 * given.snr_sigma
    assert plain.gain_dn_per_reflectance < 0.97 * gain and plain.snr < expected - 2 * plain.snr_sigma
    with pytest.raises(ValueError, match="gain"):
        measure_snr(img, truth, pixel_m=PIXEL_M, gain=-1.0)
