"""Tests of satchain.tf.ctf: Coltman's series both ways, the paper's Fourier-synthesis CTF, Table 1."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.ndimage import gaussian_filter1d
from scipy.special import ndtr, sici

from satchain.errors import ConfigError, InputError
from satchain.tf.ctf import (
    band_limited,
    coltman_ctf,
    ctf_fourier_synthesis,
    mtf_from_ctf,
    square_wave_series,
    tabulated_mtf,
)

TABLE1 = Path(__file__).resolve().parents[1].parent / "shared" / "reference" / "table1.csv"
FOUR_OVER_PI = 4.0 / math.pi
WILBRAHAM_GIBBS = 2.0 / math.pi * sici(math.pi)[0]  # (2/pi) Si(pi) = 1.178979744...

# ------------------------------------------------------------------------------------------------
# Closed-form MTF models (written here, independent of satchain.tf)
# ------------------------------------------------------------------------------------------------


def circular_diffraction(v):
    """Incoherent MTF of a clear circular pupil at normalised frequency v = f / f_c."""
    v = np.clip(np.asarray(v, dtype=float), 0.0, 1.0)
    return (2.0 / np.pi) * (np.arccos(v) - v * np.sqrt(1.0 - v * v))


def oneill_annular(v, eps):
    """O'Neill (1956) MTF of an annular pupil with obscuration ratio eps, v = f / f_c."""
    v = np.asarray(v, dtype=float)
    a = np.where(v <= 1.0, circular_diffraction(v), 0.0)
    b = np.where(v <= eps, eps**2 * circular_diffraction(v / eps), 0.0)
    phi = np.arccos(np.clip((1.0 + eps**2 - 4.0 * v**2) / (2.0 * eps), -1.0, 1.0))
    mid = (
        -2.0 * eps**2
        + (2.0 * eps / np.pi) * np.sin(phi)
        + ((1.0 + eps**2) / np.pi) * phi
        - (2.0 * (1.0 - eps**2) / np.pi) * np.arctan((1.0 + eps) / (1.0 - eps) * np.tan(phi / 2.0))
    )
    c = np.where(v <= (1.0 - eps) / 2.0, -2.0 * eps**2, np.where(v < (1.0 + eps) / 2.0, mid, 0.0))
    return (a + b + c) / (1.0 - eps**2)


def paper_system_mtf():
    """Smooth model of Table 1's MTF column (f in cy/mm): annular diffraction x two detector sincs."""
    f_c = 1.0 / (0.6496e-3 * 9.72)  # cy/mm
    pitch_mm = 5.88e-3

    def mtf(f):
        sincs = np.abs(np.sinc(f * pitch_mm) * np.sinc(f * pitch_mm * 1.0325))
        return oneill_annular(f / f_c, 0.3323) * sincs

    return band_limited(mtf, f_c)


def model(kind: str, f_c: float, p: float):
    """Band-limited MTF families for the round trips; p in [0, 1] sets the shape."""
    if kind == "diffraction":
        return band_limited(lambda f: circular_diffraction(f / f_c), f_c)
    if kind == "sinc_diffraction":
        width = (0.2 + 2.8 * p) / f_c
        return band_limited(lambda f: circular_diffraction(f / f_c) * np.abs(np.sinc(f * width)), f_c)
    scale = (0.1 + 2.0 * p) * f_c  # Gaussian truncated at the cutoff
    return band_limited(lambda f: np.exp(-((f / scale) ** 2)), f_c)


def read_table1():
    if TABLE1.is_file():  # the shared reference beside the checkout, else the copy packaged with satchain
        text = TABLE1.read_text()
    else:
        from importlib import resources

        text = (resources.files("satchain.presets") / "ankarasat3_table1.csv").read_text()
    rows = [r for r in csv.reader(text.splitlines()) if r and not r[0].startswith("#")]
    header, data = rows[0], np.array(rows[1:], dtype=float)
    col = {name: data[:, i] for i, name in enumerate(header)}
    return col["focal_freq_l_per_mm"], col["system_mtf"], col["ctf"]


def modulation(series):
    return (series.max() - series.min()) / (series.max() + series.min())


# ------------------------------------------------------------------------------------------------
# Coltman's forward series
# ------------------------------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(r=st.floats(1.0 / 3.0 + 1e-9, 1.0), f_c=st.floats(1e-3, 1e3))
def test_coltman_above_third_of_cutoff_is_four_over_pi_mtf(r, f_c):
    # Only the fundamental is below the cutoff: CTF = (4/pi) M(f) exactly.
    mtf = model("diffraction", f_c, 0.0)
    f = r * f_c
    assert coltman_ctf(f, mtf) == pytest.approx(FOUR_OVER_PI * mtf(f), rel=1e-13, abs=1e-300)


@settings(max_examples=30, deadline=None)
@given(r=st.floats(1.0 / 5.0 + 1e-9, 1.0 / 3.0), p=st.floats(0.0, 1.0))
def test_coltman_between_fifth_and_third_of_cutoff_has_two_terms(r, p):
    mtf = model("sinc_diffraction", 10.0, p)
    f = r * 10.0
    expected = FOUR_OVER_PI * (mtf(f) - mtf(3 * f) / 3.0)
    assert coltman_ctf(f, mtf) == pytest.approx(expected, rel=1e-13)


@pytest.mark.parametrize("f", [1.0, 7.3, 123.0])
def test_perfect_system_square_wave_passes_unchanged(f):
    # M = 1 up to a huge cutoff: (4/pi)(1 - 1/3 + 1/5 - ...) = 1, the alternating-series remainder being
    # bounded by the first omitted term (4/pi) / (2n + 1) with (2n + 1) f > cutoff.
    cutoff = 2e5
    perfect = band_limited(lambda g: np.ones_like(g), cutoff)
    assert abs(coltman_ctf(f, perfect) - 1.0) <= FOUR_OVER_PI * f / cutoff


def test_zero_frequency_is_the_limit_one():
    mtf = model("gaussian", 5.0, 0.5)
    assert coltman_ctf(0.0, mtf) == 1.0
    assert mtf_from_ctf(0.0, mtf) == 1.0
    assert coltman_ctf(1e-3, mtf) == pytest.approx(1.0, abs=1e-3)


def gaussian_bar_response(x0, period, sigma, n_periods=20):
    """Exact response at x0 of a 0/1 square wave (bars on [nP, nP + P/2)) blurred by a Gaussian PSF."""
    n = np.arange(-n_periods, n_periods + 1)
    return float(np.sum(ndtr((x0 - n * period) / sigma) - ndtr((x0 - n * period - period / 2) / sigma)))


@settings(max_examples=30, deadline=None)
@given(sigma_over_period=st.floats(0.01, 0.6))
def test_coltman_equals_bar_centre_modulation_of_gaussian_blur_closed_form(sigma_over_period):
    period, sigma = 1.0, sigma_over_period
    bar = gaussian_bar_response(period / 4, period, sigma)
    gap = gaussian_bar_response(3 * period / 4, period, sigma)

    def gauss(f):
        return np.exp(-2.0 * np.pi**2 * sigma**2 * f**2)

    assert coltman_ctf(1.0 / period, gauss) == pytest.approx((bar - gap) / (bar + gap), abs=1e-10)


@pytest.mark.parametrize("sigma_over_period", [0.05, 0.125, 0.25])
def test_coltman_equals_numerical_convolution_of_square_wave(sigma_over_period):
    # Real-space check: a finely sampled periodic square wave filtered by a Gaussian kernel.
    period = 4000  # samples
    sigma = sigma_over_period * period
    x = np.arange(20 * period)  # long enough for a kernel of radius 8 sigma <= 8000 samples
    wave = ((x % period) < period // 2).astype(float)
    wave[(x % (period // 2)) == 0] = 0.5  # sample on an edge: the midpoint (trapezoid rule)
    blurred = gaussian_filter1d(wave, sigma, mode="wrap", truncate=8.0)
    bar, gap = blurred[10 * period + period // 4], blurred[10 * period + 3 * period // 4]

    def gauss(f):  # MTF of that PSF, f in cy/sample
        return np.exp(-2.0 * np.pi**2 * sigma**2 * f**2)

    assert coltman_ctf(1.0 / period, gauss) == pytest.approx((bar - gap) / (bar + gap), abs=1e-4)


def test_coltman_is_vectorised_and_keeps_shape():
    mtf = model("sinc_diffraction", 3.0, 0.4)
    f = np.array([[0.05, 0.5, 1.1], [2.0, 3.5, 0.0]])
    out = coltman_ctf(f, mtf)
    assert out.shape == f.shape
    singles = np.array([[coltman_ctf(v, mtf) for v in row] for row in f])
    np.testing.assert_allclose(out, singles, rtol=1e-13, atol=1e-15)
    assert out[1, 1] == 0.0  # beyond the cutoff nothing passes


# ------------------------------------------------------------------------------------------------
# The inverse series and round trips
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("k", "b_k"),
    [(1, 1), (3, 1), (5, -1), (7, 1), (9, 0), (11, 1), (13, -1), (15, -1), (21, 1), (25, 0), (105, -1)],
)
def test_inverse_series_coefficients_match_coltman(k, b_k):
    # A CTF that is 1 only near k f picks out (pi/4) B_k / k (Coltman 1954; Boreman 2001):
    # M = (pi/4)[C(f) + C(3f)/3 - C(5f)/5 + C(7f)/7 + C(11f)/11 - C(13f)/13 - C(15f)/15 + ...]
    probe = band_limited(lambda g: (np.abs(g - k) < 0.25).astype(float), 200.0)
    assert mtf_from_ctf(1.0, probe) == pytest.approx(math.pi / 4 * b_k / k, abs=1e-15)


KINDS = st.sampled_from(["diffraction", "sinc_diffraction", "gaussian"])


@settings(max_examples=60, deadline=None)
@given(kind=KINDS, p=st.floats(0.0, 1.0), f_c=st.floats(1e-2, 1e3), r=st.floats(2e-3, 1.2))
def test_round_trip_mtf_to_ctf_to_mtf(kind, p, f_c, r):
    mtf = model(kind, f_c, p)
    ctf = band_limited(lambda g: coltman_ctf(g, mtf), f_c)
    f = r * f_c
    assert mtf_from_ctf(f, ctf) == pytest.approx(float(mtf(f)), abs=1e-6)


@settings(max_examples=60, deadline=None)
@given(kind=KINDS, p=st.floats(0.0, 1.0), f_c=st.floats(1e-2, 1e3), r=st.floats(2e-3, 1.2))
def test_round_trip_ctf_to_mtf_to_ctf(kind, p, f_c, r):
    ctf = model(kind, f_c, p)  # any band-limited curve, taken as a measured CTF
    mtf = band_limited(lambda g: mtf_from_ctf(g, ctf), f_c)
    f = r * f_c
    assert coltman_ctf(f, mtf) == pytest.approx(float(ctf(f)), abs=1e-6)


def test_round_trip_without_cutoff_uses_tolerance():
    def gauss(f):
        return np.exp(-((f / 3.0) ** 2))

    f = np.linspace(0.05, 8.0, 40)
    back = mtf_from_ctf(f, lambda g: coltman_ctf(g, gauss))
    np.testing.assert_allclose(back, gauss(f), atol=1e-9)


def test_round_trip_of_tabulated_mtf():
    f_grid = np.linspace(0.0, 100.0, 51)
    table = tabulated_mtf(f_grid, circular_diffraction(f_grid / 100.0))
    ctf = band_limited(lambda g: coltman_ctf(g, table), table.cutoff)
    f = np.linspace(0.5, 110.0, 37)
    np.testing.assert_allclose(mtf_from_ctf(f, ctf), table(f), atol=1e-12)


# ------------------------------------------------------------------------------------------------
# The paper's Fourier-synthesis method and its square-wave series
# ------------------------------------------------------------------------------------------------


def test_truncated_square_wave_modulation_tends_to_wilbraham_gibbs():
    n = 500
    # Put the series' first maximum, x = P / (4n), on a sample.
    x = np.arange(40 * n) / (40 * n)
    assert modulation(square_wave_series(x, 1.0, n_harmonics=n)) == pytest.approx(WILBRAHAM_GIBBS, abs=1e-5)
    assert WILBRAHAM_GIBBS == pytest.approx(1.178979744, abs=1e-9)


def test_truncated_square_wave_tends_to_the_bars():
    period = 16.0  # m on the ground, as in the paper's Figure 3(b)
    n = 2000
    centres = square_wave_series([period / 4, 3 * period / 4, period + period / 4], period, n_harmonics=n)
    np.testing.assert_allclose(centres, [1.0, 0.0, 1.0], atol=(2 / np.pi) / (2 * n - 1))


@pytest.mark.parametrize("kind", ["diffraction", "sinc_diffraction", "gaussian"])
def test_degraded_series_at_bar_centres_is_coltman(kind):
    # Enough harmonics to reach the cutoff: the series at the bar centre is 0.5 + 0.5 CTF_Coltman.
    f_c, period = 50.0, 0.3  # f = 3.33, harmonics up to 2n - 1 = 15.0 * f >= f_c
    mtf = model(kind, f_c, 0.5)
    bar, gap = square_wave_series([period / 4, 3 * period / 4], period, n_harmonics=8, mtf=mtf)
    ctf = coltman_ctf(1 / period, mtf)
    assert bar == pytest.approx(0.5 + 0.5 * ctf, abs=1e-14)
    assert gap == pytest.approx(0.5 - 0.5 * ctf, abs=1e-14)


def test_f_unit_scale_maps_ground_period_to_mtf_frequency():
    mtf = model("sinc_diffraction", 160.0, 0.3)  # cy/mm
    scale = 166.6667  # cy/mm per cy/m, Table 1's mapping
    x = np.linspace(0.0, 32.0, 97)
    ground = square_wave_series(x, 16.0, mtf=mtf, f_unit_scale=scale)
    normalised = square_wave_series(x / 16.0, 1.0, mtf=lambda g: mtf(g * scale / 16.0))
    np.testing.assert_allclose(ground, normalised, atol=1e-13)


@settings(max_examples=30, deadline=None)
@given(r=st.floats(1.0 / 3.0 + 1e-9, 0.999), n=st.integers(1, 20))
def test_paper_method_is_coltman_over_input_overshoot_near_cutoff(r, n):
    # Only the fundamental passes: Coltman gives (4/pi) M, the paper (4/pi) M / (input modulation).
    mtf = model("diffraction", 1.0, 0.0)
    samples = 4096
    m_in = modulation(square_wave_series(np.arange(samples) / samples, 1.0, n_harmonics=n))
    paper = ctf_fourier_synthesis(r, mtf, n_harmonics=n, samples_per_period=samples)
    assert paper == pytest.approx(coltman_ctf(r, mtf) / m_in, rel=1e-12)
    if n >= 10:
        assert paper / coltman_ctf(r, mtf) == pytest.approx(1 / WILBRAHAM_GIBBS, abs=2e-3)


def test_paper_method_with_unattenuated_harmonics_is_one():
    perfect = band_limited(lambda g: np.ones_like(g), 1e3)
    np.testing.assert_allclose(ctf_fourier_synthesis([0.0, 1.0, 50.0], perfect), 1.0, rtol=1e-13)


def test_table1_paper_method_from_tabulated_mtf():
    f, mtf_col, ctf_col = read_table1()
    paper = ctf_fourier_synthesis(f, tabulated_mtf(f, mtf_col), n_harmonics=10)
    rows = f >= 33.0
    np.testing.assert_allclose(paper[rows], ctf_col[rows], atol=3e-3)


def test_table1_paper_method_from_smooth_model():
    f, mtf_col, ctf_col = read_table1()
    mtf = paper_system_mtf()
    np.testing.assert_allclose(mtf(f), mtf_col, atol=1e-3)  # the model is Table 1's MTF
    np.testing.assert_allclose(ctf_fourier_synthesis(f, mtf), ctf_col, atol=3e-3)
    # Coltman's physical CTF is not the paper's: ~1/1.18 apart at low f, 4/pi above a third of cutoff.
    coltman = coltman_ctf(f, mtf)
    assert np.all(coltman[:4] - ctf_col[:4] > 0.08)
    near = (f > 60) & (f < 150)
    np.testing.assert_allclose(coltman[near] / mtf(f[near]), FOUR_OVER_PI, rtol=1e-12)
    np.testing.assert_allclose(ctf_col[near] / mtf_col[near], FOUR_OVER_PI / WILBRAHAM_GIBBS, atol=0.02)


def test_oneill_model_matches_numerical_pupil_autocorrelation():
    # Guards the test's own O'Neill closed form: autocorrelation of a sampled annular pupil.
    n, eps = 512, 0.3323
    x = (np.arange(n) - n // 2) * (4.0 / n)  # pupil radius 1 on a grid of half-width 2
    r = np.hypot(*np.meshgrid(x, x))
    pupil = ((r <= 1.0) & (r >= eps)).astype(float)
    otf = np.fft.ifft2(np.abs(np.fft.fft2(pupil)) ** 2).real
    shift = np.arange(n // 2)
    v = shift * (4.0 / n) / 2.0  # a shift of 2 radii is the cutoff
    np.testing.assert_allclose(otf[0, : n // 2] / otf[0, 0], oneill_annular(v, eps), atol=2e-3)


# ------------------------------------------------------------------------------------------------
# tabulated_mtf, band_limited and validation
# ------------------------------------------------------------------------------------------------


def test_tabulated_mtf_interpolates_and_is_zero_beyond_grid():
    m = tabulated_mtf([2.0, 4.0, 8.0], [0.8, 0.4, 0.2])
    np.testing.assert_allclose(m([0.0, 1.0, 3.0, 6.0, 8.0, 8.001, 100.0]), [1.0, 0.9, 0.6, 0.3, 0.2, 0, 0])
    assert m.cutoff == 8.0
    starts_at_zero = tabulated_mtf([0.0, 1.0], [0.9, 0.1])
    assert starts_at_zero(0.0) == 0.9


@pytest.mark.parametrize(
    ("f_grid", "values", "name"),
    [
        ([1.0, 1.0, 2.0], [1.0, 0.5, 0.0], "f_grid"),
        ([2.0, 1.0], [0.5, 0.0], "f_grid"),
        ([-1.0, 1.0], [0.5, 0.0], "f_grid"),
        ([0.0, np.nan], [1.0, 0.0], "f_grid"),
        ([0.0, 1.0], [1.0, np.inf], "mtf_values"),
        ([0.0, 1.0], [1.0, -0.1], "mtf_values"),
        ([0.0, 1.0], [1.0], "mtf_values"),
        ([], [], "f_grid"),
    ],
)
def test_tabulated_mtf_rejects_bad_tables(f_grid, values, name):
    with pytest.raises(InputError, match=name):
        tabulated_mtf(f_grid, values)


def test_errors_name_the_parameter():
    mtf = model("diffraction", 10.0, 0.0)
    cases = [
        (InputError, "f", lambda: coltman_ctf(-1.0, mtf)),
        (InputError, "f", lambda: coltman_ctf([1.0, np.nan], mtf)),
        (InputError, "f", lambda: mtf_from_ctf(-0.5, mtf)),
        (InputError, "f", lambda: ctf_fourier_synthesis([np.inf], mtf)),
        (ConfigError, "rtol", lambda: coltman_ctf(1.0, mtf, rtol=0.0)),
        (ConfigError, "max_terms", lambda: coltman_ctf(1.0, mtf, max_terms=0)),
        (ConfigError, "max_terms", lambda: coltman_ctf(1e-3, mtf, max_terms=100)),
        (ConfigError, "max_terms", lambda: coltman_ctf(0.5, np.sinc, max_terms=1000)),
        (ConfigError, "mtf", lambda: coltman_ctf(1.0, "not callable")),
        (ConfigError, "mtf.cutoff", lambda: coltman_ctf(1.0, band_limited(mtf, 1.0).__class__(mtf, -1.0))),
        (InputError, "mtf", lambda: coltman_ctf(1.0, lambda g: np.full_like(g, np.nan))),
        (InputError, "mtf", lambda: coltman_ctf(1.0, lambda g: g + 1j)),
        (InputError, "mtf", lambda: coltman_ctf(1.0, lambda g: np.ones((len(g), 2)))),
        (ConfigError, "n_harmonics", lambda: ctf_fourier_synthesis(1.0, mtf, n_harmonics=0)),
        (ConfigError, "n_harmonics", lambda: ctf_fourier_synthesis(1.0, mtf, n_harmonics=2.5)),
        (ConfigError, "samples_per_period", lambda: ctf_fourier_synthesis(1.0, mtf, samples_per_period=30)),
        (ConfigError, "period", lambda: square_wave_series([0.0], 0.0)),
        (ConfigError, "f_unit_scale", lambda: square_wave_series([0.0], 1.0, f_unit_scale=-2.0)),
        (InputError, "x", lambda: square_wave_series([np.nan], 1.0)),
        (ConfigError, "cutoff", lambda: band_limited(mtf, 0.0)),
        (ConfigError, "func", lambda: band_limited(3.0, 1.0)),
    ]
    for error, name, call in cases:
        with pytest.raises(error, match=rf"^{name}\b"):
            call()
