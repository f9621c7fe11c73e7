"""Motion OTFs: smear acts along y only, jitter is the FT of a Gaussian."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain.errors import ConfigError
from satchain.tf.motion import jitter_otf, smear_otf


@given(smear_um=st.floats(0.5, 30.0), f=st.floats(0.0, 300.0))
@settings(max_examples=40, deadline=None)
def test_smear_is_ft_of_uniform_segment(smear_um, f):
    L = smear_um * 1e-3
    x = np.linspace(-L / 2, L / 2, 4001)
    num = np.trapezoid(np.cos(2 * np.pi * f * x), x) / L
    assert smear_otf(0.0, f, smear_alt_m=smear_um * 1e-6) == pytest.approx(num, abs=1e-6)


def test_smear_acts_along_track_only():
    f = np.linspace(0, 200, 21)
    np.testing.assert_array_equal(smear_otf(f, 0.0, smear_alt_m=10e-6), np.ones_like(f))
    assert np.all(smear_otf(0.0, f[1:], smear_alt_m=10e-6) < 1)
    both = smear_otf(50.0, 60.0, smear_alt_m=6e-6, smear_act_m=3e-6)
    assert both == pytest.approx(np.sinc(60 * 6e-3) * np.sinc(50 * 3e-3))


def test_jitter_is_gaussian_ft():
    s_mm = 2e-3
    x = np.linspace(-12 * s_mm, 12 * s_mm, 8001)
    g = np.exp(-(x**2) / (2 * s_mm**2))
    for f in (0.0, 30.0, 85.0, 150.0):
        num = np.trapezoid(g * np.cos(2 * np.pi * f * x), x) / np.trapezoid(g, x)
        assert jitter_otf(0.0, f, rms_x_m=0.0, rms_y_m=s_mm * 1e-3) == pytest.approx(num, abs=1e-9)
    # separable and anisotropic
    assert jitter_otf(30.0, 40.0, rms_x_m=1e-6, rms_y_m=2e-6) == pytest.approx(
        jitter_otf(30.0, 0.0, rms_x_m=1e-6, rms_y_m=0.0) * jitter_otf(0.0, 40.0, rms_x_m=0.0, rms_y_m=2e-6)
    )


def test_errors_name_parameter():
    with pytest.raises(ConfigError, match=r"smear_alt_m = -1\.0"):
        smear_otf(1.0, 1.0, smear_alt_m=-1.0)
    with pytest.raises(ConfigError, match=r"rms_y_m = nan"):
        jitter_otf(1.0, 1.0, rms_x_m=0.0, rms_y_m=float("nan"))


@settings(max_examples=25, deadline=None)
@given(ny=st.integers(1, 40), nx=st.integers(1, 40), smear=st.floats(0.0, 2e-5), rms=st.floats(0.0, 1e-5))
def test_outer_grids_give_the_full_grids_floats(ny, nx, smear, rms):
    """On broadcast (outer) grids, the engine's spectra, each factor is computed once per row or column: the
    same floats as on the full grid."""
    fy = (np.fft.fftfreq(ny) * 170.0)[:, None]
    fx = (np.arange(nx) * 4.3)[None, :]
    grid = np.broadcast_arrays(fx, fy)
    full = [np.ascontiguousarray(a) for a in grid]
    for fn in (
        lambda a, b: smear_otf(a, b, smear_alt_m=smear, smear_act_m=0.3 * smear),
        lambda a, b: jitter_otf(a, b, rms_x_m=rms, rms_y_m=0.5 * rms),
    ):
        out, ref = fn(*grid), fn(*full)
        assert out.shape == ref.shape == (ny, nx)
        assert np.array_equal(out, ref)
