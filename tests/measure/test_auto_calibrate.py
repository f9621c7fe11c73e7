"""measure_auto's radiometric calibration recovers a known gain and offset through a diffraction-limited PSF.

The image is built here: the scene's exact area-coverage render at the image pixel, continued by mirroring
beyond its borders (the simulator's default border rule), filtered by the diffraction OTF of an annular pupil
in closed form (O'Neill 1956; ``tests/measure/_render.annular_mtf``, independent of satchain) -- the full,
untruncated (obscured) Airy pattern -- then ``DN = offset + gain * value``.  The Airy pattern's r^-3 tail
pulls every plateau toward its surroundings by ~1 % of the step; a straight line through the plateaus'
medians misses the gain by 0.6-2.3 %, the calibration must not.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from _render import annular_mtf
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import fftconvolve

from satchain.measure.auto import measure_auto
from satchain.scene import Scene, SlantedEdge

P = 0.5  # m per pixel
BG = 0.2
PAD = 256  # mirror margin (px) of the blurred frame


def _blur(rho: np.ndarray, q: float, eps: float) -> np.ndarray:
    """``rho`` seen through the annular pupil's diffraction (cut-off ``1 / q`` cy/px, obscuration ``eps``)."""
    a = np.pad(rho - BG, PAD, mode="symmetric")
    fy, fx = np.fft.fftfreq(a.shape[0])[:, None], np.fft.rfftfreq(a.shape[1])[None, :]
    otf = annular_mtf(np.hypot(fx, fy) * q, eps)
    return BG + np.fft.irfft2(np.fft.rfft2(a) * otf, s=a.shape)[PAD:-PAD, PAD:-PAD]


def _scene(apart: bool = False) -> Scene:
    """Two slanted edges in a 0.2 background; ``apart``: 240 m apart (their tail windows are separate)."""
    y2 = 272.0 if apart else 92.0
    items = (
        SlantedEdge("e1", center_m=(32.0, 32.0), size_m=50.0, angle_deg=5.0, measures="act"),
        SlantedEdge("e2", center_m=(32.0, y2), size_m=50.0, angle_deg=8.0, measures="alt", dark=0.1, bright=0.6),
    )
    return Scene(64.0, y2 + 32.0, items, background=BG, pixel_m=P)


@functools.lru_cache(maxsize=4)
def _blurred(q: float, eps: float, apart: bool = False) -> tuple[np.ndarray, dict]:
    """(image in reflectance seen through the pupil, truth record)."""
    scene = _scene(apart)
    return _blur(scene.render(), q, eps), scene.truth()


def _line_through_medians(cal: dict) -> tuple[float, float]:
    r = np.array([lv["reflectance"] for lv in cal["levels"]])
    m = np.array([lv["median"] for lv in cal["levels"]])
    gain, offset = np.polyfit(r, m, 1)
    return float(offset), float(gain)


@pytest.mark.parametrize(
    "q, eps, apart", [(1.07, 0.33, False), (2.0, 0.2, False), (0.7, 0.0, False), (1.07, 0.33, True)]
)
def test_gain_and_offset_recovered_through_the_diffraction_tail(q, eps, apart):
    img, truth = _blurred(q, eps, apart)
    offset, gain = 37.0, 4200.0
    cal = measure_auto(offset + gain * img, truth, pixel_m=P, ids=[]).calibration
    assert cal["fitted"] and cal["tail_fraction"] > 0.01
    assert cal["gain"] == pytest.approx(gain, rel=0.002)
    assert abs(cal["offset"] - offset) / gain < 0.002  # in reflectance
    # the effect is real: a straight line through the same areas' medians is off by more than the tolerance
    _, gain_line = _line_through_medians(cal)
    assert abs(gain_line / gain - 1) > 0.005


@settings(max_examples=8, deadline=None)
@given(offset=st.floats(-200.0, 2000.0), gain=st.floats(5.0, 5e4))
def test_calibration_is_equivariant_in_gain_and_offset(offset, gain):
    img, truth = _blurred(1.07, 0.33)
    cal = measure_auto(offset + gain * img, truth, pixel_m=P, ids=[]).calibration
    assert cal["gain"] == pytest.approx(gain, rel=0.002)
    assert abs(cal["offset"] - offset) / gain < 0.002


def test_noise_does_not_bias_the_calibration():
    img, truth = _blurred(1.07, 0.33)
    rng = np.random.default_rng(1)
    gains = []
    for _ in range(3):
        dn = 10.0 + 4000.0 * img + rng.normal(0.0, 20.0, img.shape)  # SNR ~ 40 at reflectance 0.2
        gains.append(measure_auto(dn, truth, pixel_m=P, ids=[]).calibration["gain"])
    assert np.mean(gains) == pytest.approx(4000.0, rel=0.003)


def test_compact_psf_fits_no_tail():
    """A box blur (no tail): the tail term fits ~0 and the gain is exact."""
    scene = _scene()
    rho = scene.render()
    img = BG + fftconvolve(np.pad(rho - BG, 3, mode="symmetric"), np.full((3, 3), 1 / 9), mode="same")[3:-3, 3:-3]
    cal = measure_auto(5.0 + 100.0 * img, scene.truth(), pixel_m=P, ids=[]).calibration
    assert cal["gain"] == pytest.approx(100.0, rel=1e-6) and cal["offset"] == pytest.approx(5.0, abs=1e-4)
    assert cal["tail_fraction"] is None or abs(cal["tail_fraction"]) < 1e-6


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    ny=st.integers(5, 40), nx=st.integers(5, 40), ky=st.integers(1, 5), kx=st.integers(1, 5), seed=st.integers(0, 999)
)
def test_valid_convolution_equals_the_direct_sum(ny, nx, ky, kx, seed):
    """The tail sum's FFT convolution ('valid' part) equals the direct double sum."""
    from satchain.measure.auto._calibrate import _convolve_valid

    rng = np.random.default_rng(seed)
    a, k = rng.normal(size=(ny, nx)), rng.normal(size=(ky, kx))
    direct = np.array(
        [[np.sum(a[i : i + ky, j : j + kx] * k[::-1, ::-1]) for j in range(nx - kx + 1)] for i in range(ny - ky + 1)]
    )
    np.testing.assert_allclose(_convolve_valid(a, k), direct, rtol=0, atol=1e-12 * (1 + np.abs(direct).max()))
