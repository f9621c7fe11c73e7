"""The focal-plane image (the paper's Figure 4b) against an independent full-frame FFT filter."""

import numpy as np
import pytest

from satchain import ResourceLimitError, load_preset, units
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import ArraySource
from satchain.tf.budget import SystemOTF


def _scene(n, rng):
    yy, xx = np.mgrid[0:n, 0:n]
    return 0.2 + 0.5 * (xx * np.cos(0.2) + yy * np.sin(0.2) > n / 2) + 0.05 * rng.random((n, n))


def test_focal_plane_on_input_grid_is_the_otf_filtered_input():
    s, a, n = load_preset("ankarasat3"), 0.035, 1400
    img = _scene(n, np.random.default_rng(0))
    sim = Simulator(s, input_pixel_m=a, input_shape=img.shape, params=SimParams(border="periodic"))
    fp = sim.focal_plane(sim.decimate(ArraySource(img, pixel_m=a)))
    to_mm = float(units.ground_to_focal_cy_per_mm(1.0, focal_length_m=s.focal_length_m, range_m=s.orbit.range_m)) / a
    h = SystemOTF(s)(np.fft.rfftfreq(n)[None, :] * to_mm, np.fft.fftfreq(n)[:, None] * to_mm, exclude=("detector",))
    ref = np.fft.irfft2(np.fft.rfft2(img) * h, s=(n, n))
    assert fp.shape == img.shape
    np.testing.assert_allclose(fp, ref, atol=1e-5 * np.abs(ref).max())
    coarse = sim.focal_plane(sim.decimate(ArraySource(img, pixel_m=a)), grid="coarse")
    assert coarse.shape == (n // sim.D, n // sim.D)
    # block-centre samples: between input pixels 1 and 2 of each 4 x 4 block
    mid = 0.25 * (ref[1::4, 1::4] + ref[2::4, 2::4] + ref[1::4, 2::4] + ref[2::4, 1::4])
    assert np.abs(coarse - mid).max() < 0.02 * np.abs(ref).max()


def test_focal_plane_refuses_what_does_not_fit():
    s = load_preset("ankarasat3")
    sim = Simulator(s, input_pixel_m=0.035, input_shape=(2000, 2000), params=SimParams(max_frame_bytes=2**26))
    with pytest.raises(ResourceLimitError, match="grid='coarse'"):
        sim.focal_plane(np.zeros(sim.n_coarse, np.float32))
