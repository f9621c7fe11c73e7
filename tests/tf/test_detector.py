"""Detector OTFs against independent numerical Fourier transforms of their PSFs."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate, special

from satchain.errors import ConfigError
from satchain.tf.detector import charge_diffusion_otf, pixel_otf, tdi_sync_otf


def ft_1d(psf, half_width_mm, f):
    """Numerical FT (cosine transform) of an even 1-D PSF normalised to unit area."""
    x = np.linspace(-half_width_mm, half_width_mm, 20001)
    p = psf(x)
    area = np.trapezoid(p, x)
    return np.array([np.trapezoid(p * np.cos(2 * np.pi * fi * x), x) / area for fi in np.atleast_1d(f)])


@given(width_um=st.floats(1.0, 30.0), f=st.floats(0.0, 400.0))
@settings(max_examples=40, deadline=None)
def test_pixel_otf_is_ft_of_rect(width_um, f):
    w_mm = width_um * 1e-3
    num = ft_1d(lambda x: (np.abs(x) <= w_mm / 2).astype(float), w_mm, f)[0]
    val = pixel_otf(f, 0.0, active_width_x_m=width_um * 1e-6, active_width_y_m=1e-6)
    assert val == pytest.approx(num, abs=2e-3)


def test_pixel_otf_zeros_and_axes():
    # first zero at 1/d: 170.07 cy/mm for 5.88 um; x-width acts on fx only
    assert pixel_otf(1 / 5.88e-3, 0.0, active_width_x_m=5.88e-6, active_width_y_m=5.88e-6) == pytest.approx(
        0, abs=1e-12
    )
    v = pixel_otf(0.0, 100.0, active_width_x_m=5.88e-6, active_width_y_m=2e-6)
    assert v == pytest.approx(np.sinc(100 * 2e-3))
    # at Nyquist of a 100 % fill pixel the MTF is 2/pi
    assert pixel_otf(1 / (2 * 5.88e-3), 0.0, active_width_x_m=5.88e-6, active_width_y_m=5.88e-6) == pytest.approx(
        2 / np.pi
    )
    # signed beyond the first zero
    assert pixel_otf(1.5 / 5.88e-3, 0.0, active_width_x_m=5.88e-6, active_width_y_m=5.88e-6) < 0


def test_charge_diffusion_is_hankel_transform_of_exponential_psf():
    L_mm = 3e-3
    for f in (0.0, 20.0, 80.0, 200.0):
        # 2-D isotropic PSF exp(-r/L)/(2 pi L^2): OTF = 2 pi int_0^inf psf(r) J0(2 pi f r) r dr
        val, _ = integrate.quad(
            lambda r, f=f: np.exp(-r / L_mm) / (2 * np.pi * L_mm**2) * special.j0(2 * np.pi * f * r) * 2 * np.pi * r,
            0,
            60 * L_mm,
            limit=400,
        )
        assert charge_diffusion_otf(f, 0.0, diffusion_length_m=L_mm * 1e-3) == pytest.approx(val, abs=1e-6)
    # isotropic
    assert charge_diffusion_otf(30.0, 40.0, diffusion_length_m=3e-6) == pytest.approx(
        charge_diffusion_otf(50.0, 0.0, diffusion_length_m=3e-6)
    )


def test_tdi_sync_is_linear_smear_of_n_times_error_pixels():
    p = 5.88e-6
    f = np.linspace(0, 170, 50)
    got = tdi_sync_otf(0.0, f, stages=32, sync_error=0.01, pitch_y_m=p)
    np.testing.assert_allclose(got, np.sinc(0.32 * p * 1e3 * f), atol=1e-14)
    # across-track frequencies are untouched, and the sign of the error does not matter
    assert tdi_sync_otf(80.0, 0.0, stages=32, sync_error=0.05, pitch_y_m=p) == 1.0
    np.testing.assert_allclose(
        tdi_sync_otf(0.0, f, stages=8, sync_error=-0.02, pitch_y_m=p),
        tdi_sync_otf(0.0, f, stages=8, sync_error=0.02, pitch_y_m=p),
    )


@pytest.mark.parametrize(
    ("call", "msg"),
    [
        (
            lambda: pixel_otf(1.0, 1.0, active_width_x_m=0.0, active_width_y_m=1e-6),
            r"active_width_x_m = 0\.0",
        ),
        (lambda: charge_diffusion_otf(1.0, 1.0, diffusion_length_m=-1e-6), r"diffusion_length_m = -1e-06"),
        (lambda: tdi_sync_otf(1.0, 1.0, stages=0, sync_error=0.0, pitch_y_m=1e-6), r"stages = 0"),
        (lambda: tdi_sync_otf(1.0, 1.0, stages=4, sync_error=0.7, pitch_y_m=1e-6), r"sync_error = 0\.7"),
    ],
)
def test_errors_name_parameter(call, msg):
    with pytest.raises(ConfigError, match=msg):
        call()
