"""The sign convention of ``optics.zernike_rms_waves`` (issue 29, item 20): a tilt moves the image by its closed form
``4 c lambda F#`` (Noll's Z2 = 2 rho cos theta: a wavefront slope of 4 c lambda / D), towards +x (ACT, increasing
column) for a positive Z2 and +y (ALT, increasing row) for a positive Z3; ``zernike_sign = "zemax"`` (Zemax
OpticStudio's FFT PSF, GalSim's default fft_sign) is W -> -W, which for a real pupil is the PSF rotated by 180 degrees
(the OTF's complex conjugate)."""

from __future__ import annotations

import numpy as np
import pytest

from satchain.config.system import ImagingSystem
from satchain.engine.degrade import simulate_image
from satchain.errors import ConfigError
from satchain.tf.optics import make_diffraction_otf
from satchain.tf.pupil import PupilParams

LAMBDA_M, F_NUMBER, PITCH_M = 6.5e-7, 9.72, 5.88e-6


def _system(zernikes, sign=None, spiders=None):
    optics = {
        "aperture_diameter_m": 0.7,
        "f_number": F_NUMBER,
        "obscuration_ratio": 0.33,
        "wavelengths_m": [LAMBDA_M],
        "zernike_rms_waves": zernikes,
    }
    if sign is not None:
        optics["zernike_sign"] = sign
    if spiders is not None:
        optics["spiders"] = spiders
    return ImagingSystem.from_dict({"orbit": {"altitude_m": 567e3}, "optics": optics, "detector": {"pitch_m": PITCH_M}})


def _centroid_px(system) -> np.ndarray:
    """(x, y) centroid of the simulated image of a 1-GSD bright square on a dark field (noise-free, px)."""
    n, q = 320, 8  # scene pixels; scene pixels per GSD
    scene = np.full((n, n), 0.1)
    scene[n // 2 - q // 2 : n // 2 + q // 2, n // 2 - q // 2 : n // 2 + q // 2] = 0.9
    image = np.asarray(simulate_image(scene, system, pixel_m=system.gsd_m / q).image, dtype=float)
    image = image - np.median(image)
    yy, xx = np.mgrid[0 : image.shape[0], 0 : image.shape[1]]
    return np.array([(image * xx).sum(), (image * yy).sum()]) / image.sum()


def test_a_tilt_moves_the_image_by_its_closed_form_and_zemax_sign_moves_it_the_other_way():
    a = 0.1  # waves rms of Noll Z2 / Z3
    shift_px = 4 * a * LAMBDA_M * F_NUMBER / PITCH_M  # W = 2 a rho cos(theta) waves: slope 4 a lambda / D rad
    ref = _centroid_px(_system({}))
    d_z2 = _centroid_px(_system({2: a})) - ref
    d_z3 = _centroid_px(_system({3: a})) - ref
    d_zemax = _centroid_px(_system({2: a}, sign="zemax")) - ref
    assert d_z2[0] == pytest.approx(shift_px, rel=0.03) and abs(d_z2[1]) < 1e-3  # +x: ACT, increasing column
    assert d_z3[1] == pytest.approx(shift_px, rel=0.03) and abs(d_z3[0]) < 1e-3  # +y: ALT, increasing row
    assert d_zemax[0] == pytest.approx(-shift_px, rel=0.03) and abs(d_zemax[1]) < 1e-3


@pytest.mark.parametrize("spiders", [None, {"count": 3, "width_m": 0.03, "angle_deg": 10.0}])
def test_zemax_sign_is_the_psf_rotated_by_180_degrees(spiders):
    """W -> -W on a real pupil is PSF(x) -> PSF(-x): the OTF becomes its complex conjugate, even with three vanes
    (a pupil that is not centrosymmetric), and even terms alone are unchanged."""
    z = {2: 0.05, 4: 0.08, 6: -0.04, 8: 0.03, 9: 0.02, 11: 0.03}
    params = PupilParams(samples_across_pupil=64)
    fx, fy = np.meshgrid(np.linspace(-160, 160, 17), np.linspace(-160, 160, 13))
    ours = make_diffraction_otf(_system(z, spiders=spiders).optics, params=params)(fx, fy)
    zemax = make_diffraction_otf(_system(z, "zemax", spiders).optics, params=params)(fx, fy)
    assert np.max(np.abs(ours.imag)) > 0.05  # the odd terms give the OTF a phase
    np.testing.assert_allclose(zemax, np.conj(ours), atol=1e-12)
    even = {4: 0.08, 6: -0.04, 11: 0.03}
    np.testing.assert_allclose(
        make_diffraction_otf(_system(even, "zemax").optics, params=params)(fx, fy),
        make_diffraction_otf(_system(even).optics, params=params)(fx, fy),
        atol=1e-12,
    )


def test_zernike_sign_is_validated_and_round_trips():
    with pytest.raises(ConfigError, match=r"optics\.zernike_sign = 'galsim'"):
        _system({2: 0.1}, sign="galsim")
    s = _system({2: 0.1, 4: 0.05}, sign="zemax")
    assert s.optics.wavefront_zernikes_waves == {2: -0.1, 4: -0.05}
    assert ImagingSystem.from_dict(s.to_dict()).optics.zernike_sign == "zemax"
    assert _system({}).optics.zernike_sign == "satchain"
