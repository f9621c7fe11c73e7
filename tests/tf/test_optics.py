"""Physics tests of satchain.tf.optics against closed forms and independent numerical integrals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.special import j0, j1

from satchain.config.system import Optics, Spiders
from satchain.errors import ConfigError, InputError, ResourceLimitError
from satchain.tf.optics import (
    PupilOTF,
    PupilParams,
    annular_mtf,
    diffraction_otf,
    make_diffraction_otf,
    noll_to_nm,
    optical_cutoff_cy_per_mm,
    pupil_otf,
    pupil_psf,
    shannon_atf,
    zernike_noll,
)

LAM_M, FNO, D_M = 500e-9, 10.0, 0.1
FC = 1.0 / (LAM_M * FNO * 1e3)  # 200 cy/mm, written out independently of the code
AIRY_ZERO = 1.2196698912665045  # first zero of J1(pi r) / (pi r), r in lambda F#
PUPIL = dict(wavelength_m=LAM_M, f_number=FNO, aperture_diameter_m=D_M)


def circular_mtf(v):
    v = np.clip(v, 0, 1)
    return (2 / np.pi) * (np.arccos(v) - v * np.sqrt(1 - v**2))


def lens_area(r1: float, r2: float, d: float) -> float:
    """Area common to disks of radii r1 (centre 0) and r2 (centre d on x), by 1-D quadrature of chords."""
    lo, hi = max(-r1, d - r2), min(r1, d + r2)
    if hi <= lo:
        return 0.0

    def chord(x):
        a = math.sqrt(max(r1 * r1 - x * x, 0.0))
        b = math.sqrt(max(r2 * r2 - (x - d) ** 2, 0.0))
        return 2.0 * min(a, b)

    pts = [(r1 * r1 - r2 * r2 + d * d) / (2 * d)] if d > 0 else None
    pts = [p for p in (pts or []) if lo < p < hi] or None
    return quad(chord, lo, hi, points=pts, epsabs=1e-13, epsrel=1e-12, limit=200)[0]


def annulus_overlap_mtf(v: float, eps: float) -> float:
    """Normalised area of overlap of an annulus (outer radius 1) with itself displaced by 2 v."""
    d = 2 * v
    inter = lens_area(1, 1, d) - 2 * lens_area(1, eps, d) + lens_area(eps, eps, d)
    return inter / (math.pi * (1 - eps * eps))


def hopkins_defocus_otf(v: float, c_rms_waves: float) -> float:
    """OTF of a clear pupil with Noll-4 defocus c: the overlap integral, whose phase is linear in the
    pupil coordinate (Hopkins 1955), so it reduces to a 1-D cosine transform of the chord length."""
    s = 2 * v

    def g(t):
        return (
            2
            * math.sqrt(max(0.0, 1 - (abs(t) + s / 2) ** 2))
            * math.cos(8 * math.sqrt(3) * math.pi * c_rms_waves * s * t)
        )

    return quad(g, -(1 - s / 2), 1 - s / 2, points=[0.0], limit=400, epsabs=1e-12)[0] / math.pi


# -------------------------------------------------------------------------- closed form (O'Neill)
def test_annular_eps0_is_circular_formula_and_known_values():
    f = np.linspace(0, FC, 501)
    np.testing.assert_allclose(annular_mtf(f, wavelength_m=LAM_M, f_number=FNO), circular_mtf(f / FC), atol=1e-14)
    # textbook values of the circular-pupil MTF: v = 0.25, 0.5, 0.75
    got = annular_mtf(np.array([0.25, 0.5, 0.75]) * FC, wavelength_m=LAM_M, f_number=FNO)
    np.testing.assert_allclose(got, [0.685038, 0.391002, 0.144294], atol=2e-6)


@pytest.mark.parametrize("eps", [0.0, 1e-9, 0.2, 0.33, 0.5, 0.9])
def test_annular_normalisation_cutoff_and_range(eps):
    f = np.linspace(-1.5 * FC, 1.5 * FC, 3001)
    m = annular_mtf(f, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps)
    assert float(annular_mtf(0.0, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps)) == pytest.approx(
        1.0, abs=1e-14
    )
    assert np.all(m[np.abs(f) >= FC] == 0.0)
    assert np.all((m >= 0) & (m <= 1))
    np.testing.assert_array_equal(m, annular_mtf(-f, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps))


def test_annular_eps0_is_monotone_decreasing():
    m = annular_mtf(np.linspace(0, FC, 4001), wavelength_m=LAM_M, f_number=FNO)
    assert np.all(np.diff(m) < 0)


@pytest.mark.parametrize("eps", [0.1, 0.33, 0.5, 0.8])
def test_annular_is_continuous_at_region_boundaries(eps):
    for v in (eps, (1 - eps) / 2, (1 + eps) / 2):
        v_pair = np.array([v - 1e-12, v + 1e-12])
        m = annular_mtf(v_pair * FC, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps)
        assert abs(m[1] - m[0]) < 1e-9
        assert m[0] == pytest.approx(annulus_overlap_mtf(v, eps), abs=1e-9)


def test_annular_small_obscuration_tends_to_circular():
    f = np.linspace(0, FC, 2001)
    for eps in (1e-3, 1e-6):
        m = annular_mtf(f, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps)
        assert np.max(np.abs(m - circular_mtf(f / FC))) < 3 * eps


@settings(max_examples=60, deadline=None)
@given(eps=st.floats(0.0, 0.95), v=st.floats(0.0, 1.0))
def test_annular_equals_overlap_area_of_annuli(eps, v):
    m = float(annular_mtf(v * FC, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps))
    assert m == pytest.approx(annulus_overlap_mtf(v, eps), abs=2e-9)


def test_optical_cutoff():
    assert optical_cutoff_cy_per_mm(LAM_M, FNO) == pytest.approx(FC, rel=1e-14)


# -------------------------------------------------------------------------- pupil FFT vs closed form
@pytest.fixture(scope="module", params=[0.0, 0.33, 0.5])
def clear_otf(request):
    return request.param, PupilOTF(**PUPIL, obscuration_ratio=request.param)


def test_pupil_fft_grid_matches_oneill(clear_otf):
    eps, otf = clear_otf
    n = (otf.grid.shape[0] - 1) // 2
    k = np.arange(-n, n + 1) / n
    v = np.hypot(k[:, None], k[None, :])
    ref = np.vectorize(lambda x: annulus_overlap_mtf(min(x, 1.0), eps) if x < 1 else 0.0)(v[n, n::4])
    # the raw FFT autocorrelation at its lags (no interpolation involved): along +x exactly vs quadrature
    assert np.max(np.abs(otf.grid[n, n::4] - ref)) < 1e-3
    # and everywhere on the 2-D lag grid vs the closed form
    assert (
        np.max(np.abs(otf.grid - annular_mtf(v * FC, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps))) < 1e-3
    )


@pytest.mark.parametrize("angle_deg", [0.0, 17.0, 45.0, 90.0, 133.0, 210.0, 301.0])
def test_pupil_fft_matches_oneill_along_directions(clear_otf, angle_deg):
    eps, otf = clear_otf
    f = np.linspace(0, 1.1 * FC, 1501)
    a = math.radians(angle_deg)
    got = otf(f * math.cos(a), f * math.sin(a))
    ref = annular_mtf(f, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps)
    assert np.max(np.abs(got - ref)) < 1e-3
    assert np.all(got[f >= FC] == 0)


def test_pupil_fft_matches_oneill_at_random_2d_frequencies(clear_otf):
    eps, otf = clear_otf
    rng = np.random.default_rng(1)
    fx, fy = rng.uniform(-FC, FC, (2, 20000))
    ref = annular_mtf(np.hypot(fx, fy), wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=eps)
    assert np.max(np.abs(otf(fx, fy) - ref)) < 1e-3


def test_pupil_otf_function_broadcasts():
    fx = np.linspace(0, 150, 4)[None, :]
    fy = np.linspace(0, 150, 3)[:, None]
    params = PupilParams(samples_across_pupil=128)
    out = pupil_otf(fx, fy, **PUPIL, obscuration_ratio=0.3, params=params)
    assert out.shape == (3, 4) and np.iscomplexobj(out)
    ref = annular_mtf(np.hypot(fx, fy), wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=0.3)
    assert np.max(np.abs(out - ref)) < 3e-3


# -------------------------------------------------------------------------- PSF (eq. 1)
@pytest.fixture(scope="module")
def airy_psf():
    return pupil_psf(**PUPIL, samples_per_lambda_f_number=16, params=PupilParams(samples_across_pupil=64))


def test_psf_first_zero_is_airy_radius(airy_psf):
    c, p = airy_psf.centre_index, airy_psf.psf_per_m2
    for profile in (p[c, c:], p[c:, c], p[c, c::-1]):
        first_min = int(np.argmax(np.diff(profile) > 0))
        r = first_min * airy_psf.spacing_m
        assert abs(r - AIRY_ZERO * LAM_M * FNO) <= airy_psf.spacing_m


def test_psf_peak_and_encircled_energy_match_airy(airy_psf):
    c, p = airy_psf.centre_index, airy_psf.psf_per_m2
    # eq. 1 peak: area / (lambda f)^2 = pi / (4 lambda^2 F#^2)
    assert p[c, c] == pytest.approx(math.pi / (4 * LAM_M**2 * FNO**2), rel=1e-3)
    x = airy_psf.x_m
    r = np.hypot(x[None, :], x[:, None])
    for r_lf in (AIRY_ZERO, 2.0, 5.0):
        ee = p[r <= r_lf * LAM_M * FNO].sum() * airy_psf.spacing_m**2
        z = math.pi * r_lf
        assert ee == pytest.approx(1 - j0(z) ** 2 - j1(z) ** 2, abs=2e-3)  # Rayleigh's encircled energy


def test_psf_tilt_moves_peak_towards_plus_x_and_plus_y():
    params = PupilParams(samples_across_pupil=64)
    # Noll 2 = 2 rho cos(theta): W = 4 c x / D waves -> PSF shift 4 c lambda F#
    psf = pupil_psf(**PUPIL, zernike_rms_waves={2: 0.5}, samples_per_lambda_f_number=8, params=params)
    iy, ix = np.unravel_index(np.argmax(psf.psf_per_m2), psf.psf_per_m2.shape)
    assert (iy - psf.centre_index, ix - psf.centre_index) == (0, 16)
    psf = pupil_psf(**PUPIL, zernike_rms_waves={3: -0.25}, samples_per_lambda_f_number=8, params=params)
    iy, ix = np.unravel_index(np.argmax(psf.psf_per_m2), psf.psf_per_m2.shape)
    assert (iy - psf.centre_index, ix - psf.centre_index) == (-8, 0)


# -------------------------------------------------------------------------- Zernike
def test_noll_ordering_table():
    table = {1: (0, 0), 2: (1, 1), 3: (1, -1), 4: (2, 0), 5: (2, -2), 6: (2, 2), 7: (3, -1), 8: (3, 1),
             9: (3, -3), 10: (3, 3), 11: (4, 0), 12: (4, 2), 13: (4, -2), 14: (4, 4), 15: (4, -4),
             22: (6, 0)}  # fmt: skip
    assert {j: noll_to_nm(j) for j in table} == table


def test_zernike_explicit_forms():
    rho = np.linspace(0, 1, 7)[:, None]
    th = np.linspace(0, 2 * np.pi, 9)[None, :]
    explicit = {
        1: np.ones_like(rho * th),
        2: 2 * rho * np.cos(th),
        4: math.sqrt(3) * (2 * rho**2 - 1),
        5: math.sqrt(6) * rho**2 * np.sin(2 * th),
        7: math.sqrt(8) * (3 * rho**3 - 2 * rho) * np.sin(th),
        11: math.sqrt(5) * (6 * rho**4 - 6 * rho**2 + 1),
        12: math.sqrt(10) * (4 * rho**4 - 3 * rho**2) * np.cos(2 * th),
    }
    for j, z in explicit.items():
        np.testing.assert_allclose(zernike_noll(j, rho, th), np.broadcast_to(z, (7, 9)), atol=1e-12)


def test_zernike_orthonormal_over_unit_disk():
    x, w = np.polynomial.legendre.leggauss(24)
    rho, w_rho = (x + 1) / 2, w / 2
    nth = 64
    th = np.arange(nth) * 2 * np.pi / nth
    weight = (w_rho * rho)[:, None] * np.full(nth, 2 * np.pi / nth)[None, :] / np.pi
    zs = np.array([zernike_noll(j, rho[:, None], th[None, :]) for j in range(1, 29)])
    gram = np.einsum("iab,jab,ab->ij", zs, zs, weight)
    np.testing.assert_allclose(gram, np.eye(28), atol=1e-10)


# -------------------------------------------------------------------------- aberrations
@pytest.mark.parametrize("c_waves", [0.1, 0.25])
def test_defocus_matches_hopkins_integral_and_lowers_mtf(c_waves):
    otf = PupilOTF(**PUPIL, zernike_rms_waves={4: c_waves})
    for v in (0.1, 0.3, 0.5, 0.8):
        for a in (0.0, 1.0):
            got = otf(v * FC * math.cos(a), v * FC * math.sin(a))
            assert abs(got - hopkins_defocus_otf(v, c_waves)) < 1e-3
    mid = np.linspace(0.2, 0.6, 9) * FC
    assert np.all(np.abs(otf(mid, 0 * mid)) < circular_mtf(mid / FC) - 0.05)


def test_tilt_changes_only_the_phase():
    params = PupilParams(samples_across_pupil=256)
    c = 0.05  # waves rms of Noll 2 -> PSF shift x0 = 4 c lambda F#
    tilted = PupilOTF(**PUPIL, zernike_rms_waves={2: c}, params=params)
    rng = np.random.default_rng(3)
    fx, fy = rng.uniform(-FC, FC, (2, 5000))
    got = tilted(fx, fy)
    ref = annular_mtf(np.hypot(fx, fy), wavelength_m=LAM_M, f_number=FNO)
    x0_mm = 4 * c * LAM_M * FNO * 1e3
    np.testing.assert_allclose(got, ref * np.exp(-2j * np.pi * fx * x0_mm), atol=2e-3)
    np.testing.assert_allclose(np.abs(got), np.abs(PupilOTF(**PUPIL, params=params)(fx, fy)), atol=5e-5)


def test_aberrated_spider_otf_invariants():
    sp = Spiders(count=3, width_m=0.004, angle_deg=20.0)
    otf = PupilOTF(**PUPIL, obscuration_ratio=0.3, spiders=sp, zernike_rms_waves={7: 0.08, 5: -0.05},
                   params=PupilParams(samples_across_pupil=256))  # fmt: skip
    assert otf(0.0, 0.0) == pytest.approx(1.0, abs=1e-12)
    rng = np.random.default_rng(4)
    fx, fy = rng.uniform(-1.2 * FC, 1.2 * FC, (2, 20000))
    o = otf(fx, fy)
    np.testing.assert_allclose(otf(-fx, -fy), np.conj(o), atol=1e-12)  # hermitian: the PSF is real
    assert np.all(np.abs(o) <= 1 + 1e-12)
    assert np.abs(o.imag).max() > 1e-3  # coma gives a phase
    assert np.all(o[np.hypot(fx, fy) >= FC] == 0)


# -------------------------------------------------------------------------- spiders
def _binary_pupil_overlap(k_px, eps, width_px, shifts):
    """Independent reference: point-sampled binary pupil, 4 vanes along the axes, overlap by counting."""
    c = np.arange(k_px) - (k_px - 1) / 2
    x, y = c[None, :], c[:, None]
    r = np.hypot(x, y)
    p = (r <= k_px / 2) & (r >= eps * k_px / 2)
    p &= ~((np.abs(y) <= width_px / 2) | (np.abs(x) <= width_px / 2))
    q = np.zeros((2 * k_px, 2 * k_px), bool)
    q[:k_px, :k_px] = p
    return [float((q & np.roll(q, (sy, sx), axis=(0, 1))).sum() / p.sum()) for sx, sy in shifts]


def test_four_vane_spider_matches_overlap_count():
    k_px = 1024
    width_px = 40  # an exact number of reference pixels
    sp = Spiders(count=4, width_m=D_M * width_px / k_px, angle_deg=0.0)
    otf = PupilOTF(**PUPIL, obscuration_ratio=0.3, spiders=sp)
    shifts = [(256, 0), (0, 256), (200, 200), (100, 300), (600, 100)]
    ref = _binary_pupil_overlap(k_px, 0.3, width_px, shifts)
    for (sx, sy), r in zip(shifts, ref, strict=True):
        assert abs(otf(sx / k_px * FC, sy / k_px * FC) - r) < 1e-3
    # the vanes remove area, so the cusp is steeper: the spider MTF is below the annulus MTF at low f
    annulus = annular_mtf(0.05 * FC, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=0.3)
    assert abs(otf(0.05 * FC, 0.0)) < annulus - 1e-3


def test_spider_mtf_has_the_symmetry_of_the_vanes():
    params = PupilParams(samples_across_pupil=256)
    f = np.linspace(0.02, 0.98, 49) * FC

    def mtf(o, deg):
        a = math.radians(deg)
        return np.abs(o(f * math.cos(a), f * math.sin(a)))

    cross = PupilOTF(**PUPIL, obscuration_ratio=0.3, spiders=Spiders(count=4, width_m=0.005), params=params)
    np.testing.assert_allclose(mtf(cross, 90.0), mtf(cross, 0.0), atol=1e-9)  # exact on the grid
    assert np.max(np.abs(mtf(cross, 45.0) - mtf(cross, 0.0))) > 5e-3  # anisotropic
    tri = PupilOTF(**PUPIL, spiders=Spiders(count=3, width_m=0.005, angle_deg=90.0), params=params)
    for deg in (10.0, 35.0):  # 3 vanes + hermitian symmetry -> period 60 deg
        np.testing.assert_allclose(mtf(tri, deg + 60.0), mtf(tri, deg), atol=1.5e-3)
        np.testing.assert_allclose(mtf(tri, 180.0 - deg + 2 * 90.0), mtf(tri, deg), atol=1.5e-3)  # mirror
    assert np.max(np.abs(mtf(tri, 0.0) - mtf(tri, 30.0))) > 5e-3


# -------------------------------------------------------------------------- polychromatic, ATF
def test_polychromatic_is_weighted_sum_of_closed_forms():
    o = Optics(aperture_diameter_m=D_M, f_number=FNO, obscuration_ratio=0.25,
               wavelengths_m=(450e-9, 700e-9), wavelength_weights=(3.0, 1.0))  # fmt: skip
    f = np.linspace(0, 250, 101)
    ref = 0.75 * annular_mtf(f, wavelength_m=450e-9, f_number=FNO, obscuration_ratio=0.25)
    ref += 0.25 * annular_mtf(f, wavelength_m=700e-9, f_number=FNO, obscuration_ratio=0.25)
    got = diffraction_otf(f * 0.6, f * 0.8, o)
    assert got.dtype == np.float64
    np.testing.assert_allclose(got, ref, atol=1e-14)


def test_polychromatic_pupil_fft_is_weighted_sum_with_scaled_wavefront():
    params = PupilParams(samples_across_pupil=128)
    sp = Spiders(count=4, width_m=0.003, angle_deg=10.0)
    o = Optics(aperture_diameter_m=D_M, f_number=FNO, wavelengths_m=(450e-9, 750e-9),
               wavelength_weights=(1.0, 3.0), spiders=sp, zernike_rms_waves={4: 0.05})  # fmt: skip
    lam_eff = 0.25 * 450e-9 + 0.75 * 750e-9
    fx, fy = np.meshgrid(np.linspace(-200, 200, 9), np.linspace(-150, 150, 7))
    ref = sum(
        w
        * pupil_otf(
            fx,
            fy,
            wavelength_m=lam,
            f_number=FNO,
            aperture_diameter_m=D_M,
            spiders=sp,
            zernike_rms_waves={4: 0.05 * lam_eff / lam},
            params=params,
        )  # fmt: skip
        for w, lam in ((0.25, 450e-9), (0.75, 750e-9))
    )
    np.testing.assert_allclose(make_diffraction_otf(o, params=params)(fx, fy), ref, atol=1e-12)


def test_random_wfe_multiplies_by_shannon_atf():
    w = 0.06
    o = Optics(aperture_diameter_m=D_M, f_number=FNO, wavelengths_m=(LAM_M,), wfe_rms_waves=w)
    v = np.linspace(0, 1, 41)
    atf = 1 - (w / 0.18) ** 2 * (1 - 4 * (v - 0.5) ** 2)
    np.testing.assert_allclose(diffraction_otf(v * FC, 0.0, o), circular_mtf(v) * atf, atol=1e-13)


def test_analytic_and_pupil_fft_models_agree_for_an_optics():
    kw = dict(aperture_diameter_m=D_M, f_number=FNO, obscuration_ratio=0.33, wavelengths_m=(500e-9, 600e-9))
    fx, fy = np.random.default_rng(5).uniform(-FC, FC, (2, 3000))
    a = diffraction_otf(fx, fy, Optics(**kw, diffraction_model="analytic"))
    b = diffraction_otf(fx, fy, Optics(**kw, diffraction_model="pupil_fft"))
    assert np.max(np.abs(a - b)) < 1e-3


def test_shannon_atf_closed_form_points():
    for w in (0.02, 0.07, 0.15):
        assert shannon_atf(0.0, w) == pytest.approx(1.0, abs=1e-15)
        assert shannon_atf(1.0, w) == pytest.approx(1.0, abs=1e-15)
        assert shannon_atf(0.5, w) == pytest.approx(1 - (w / 0.18) ** 2, abs=1e-15)
        v = np.linspace(0, 1, 1001)
        a = shannon_atf(v, w)
        assert np.argmin(a) == 500
        np.testing.assert_allclose(a, a[::-1], atol=1e-15)
    assert np.all(shannon_atf(np.linspace(0, 2, 11), 0.0) == 1.0)
    assert float(shannon_atf(0.5, 0.25)) == 0.0  # clipped at 0 beyond W = 0.18


# -------------------------------------------------------------------------- errors
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(wavelength_m=-5e-7), "wavelength_m"),
        (dict(f_number=0.0), "f_number"),
        (dict(aperture_diameter_m=float("nan")), "aperture_diameter_m"),
        (dict(obscuration_ratio=1.0), "obscuration_ratio"),
        (dict(obscuration_ratio=-0.1), "obscuration_ratio"),
        (dict(zernike_rms_waves={0: 0.1}), "Noll index"),
        (dict(zernike_rms_waves={4: float("inf")}), "zernike_rms_waves[4]"),
        (dict(spiders=Spiders(count=2, width_m=0.2)), "spiders.width_m"),
    ],
)
def test_bad_pupil_parameters_name_the_parameter(kwargs, name):
    with pytest.raises(ConfigError, match=name.replace("[", r"\[").replace("]", r"\]")):
        PupilOTF(**{**PUPIL, **kwargs}, params=PupilParams(samples_across_pupil=16))
    if "zernike" not in name and "spiders" not in name:
        with pytest.raises(ConfigError, match=name):
            pupil_psf(**{**PUPIL, **kwargs}, params=PupilParams(samples_across_pupil=16))


def test_other_errors():
    with pytest.raises(ConfigError, match="wavelength_m"):
        annular_mtf(1.0, wavelength_m=-1.0, f_number=FNO)
    with pytest.raises(ConfigError, match="obscuration_ratio = 1.2"):
        annular_mtf(1.0, wavelength_m=LAM_M, f_number=FNO, obscuration_ratio=1.2)
    with pytest.raises(InputError, match="f_cy_per_mm"):
        annular_mtf([1.0, np.nan], wavelength_m=LAM_M, f_number=FNO)
    with pytest.raises(ConfigError, match="samples_across_pupil"):
        PupilParams(samples_across_pupil=8)
    with pytest.raises(ConfigError, match="samples_per_lambda_f_number"):
        pupil_psf(**PUPIL, samples_per_lambda_f_number=0)
    with pytest.raises(ConfigError, match="wfe_rms_waves"):
        shannon_atf(0.5, -0.1)
    with pytest.raises(ConfigError, match="Noll index"):
        zernike_noll(0, 0.5, 0.0)
    otf = PupilOTF(**PUPIL, params=PupilParams(samples_across_pupil=16))
    with pytest.raises(InputError, match="fx_cy_per_mm"):
        otf(np.zeros(3), np.zeros(4))


def test_oversized_fft_is_refused_up_front_saying_how_much():
    with pytest.raises(ResourceLimitError, match=r"needs about 143\.\d\d GiB"):
        PupilOTF(**PUPIL, params=PupilParams(samples_across_pupil=20000))
    with pytest.raises(ResourceLimitError, match="max_fft_bytes"):
        pupil_psf(**PUPIL, samples_per_lambda_f_number=8, params=PupilParams(samples_across_pupil=4096))


@settings(max_examples=25, deadline=None)
@given(
    ny=st.integers(8, 90),
    nx=st.integers(1, 40),
    centred=st.booleans(),
    obscuration=st.sampled_from([0.0, 0.3]),
    wfe=st.sampled_from([0.0, 0.05]),
)
def test_otf_on_an_outer_grid_equals_the_full_grid_bitwise(ny, nx, centred, obscuration, wfe):
    """A clear or obscured pupil's OTF is computed once per distinct |fy| row on an outer grid (broadcast
    views: the engine's spectra): the same floats as on the full grid, mirrored rows or not."""
    o = Optics(aperture_diameter_m=0.1, f_number=10.0, wavelengths_m=(450e-9, 600e-9),
               obscuration_ratio=obscuration, wfe_rms_waves=wfe)  # fmt: skip
    otf = make_diffraction_otf(o)
    m = np.fft.fftfreq(ny) * ny if centred else np.arange(ny, dtype=float)
    fy = (m * 7.3)[:, None]
    fx = (np.arange(nx) * 5.1)[None, :]
    grid = np.broadcast_arrays(fx, fy)
    full = [np.ascontiguousarray(a) for a in grid]
    assert np.array_equal(otf(*grid), otf(*full))
