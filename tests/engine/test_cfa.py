"""Issue 32, point 4: image formation through a Bayer colour filter array (satchain.engine.cfa).

The mosaic keeps exactly each colour's photosites (positions written out here per pattern, not taken from the
code); mosaic -> demosaic of a uniform grey (or uniform colour) scene gives it back exactly for every method and
pattern; each raw colour plane, sampled from a slanted edge rendered analytically at the photosite grid (an
error-function edge of a known Gaussian blur convolved exactly with the square photosite, in closed form) and
measured with satchain.measure.edge on the plane's own grid, has the MTF that satchain.tf.cfa predicts at its
Nyquist within 0.02; a neutral edge shows false colour after demosaicing, more with bilinear interpolation
than with Malvar 2004 or Menon 2007.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ndtr

from satchain.engine.cfa import DEMOSAIC_METHODS, cfa_masks, demosaic, false_colour_amplitude, luminance, mosaic
from satchain.errors import InputError
from satchain.measure.edge import measure_edge
from satchain.tf.cfa import grid_nyquist_cy_per_px, nyquist_cy_per_px, plane_mtf

PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")
METHODS = tuple(DEMOSAIC_METHODS)

#: (row, col) of each colour in the 2x2 cell, written out from the pattern names (Bayer 1976).
SITES = {
    "RGGB": {"red": [(0, 0)], "green": [(0, 1), (1, 0)], "blue": [(1, 1)]},
    "GRBG": {"red": [(0, 1)], "green": [(0, 0), (1, 1)], "blue": [(1, 0)]},
    "GBRG": {"red": [(1, 0)], "green": [(0, 0), (1, 1)], "blue": [(0, 1)]},
    "BGGR": {"red": [(1, 1)], "green": [(0, 1), (1, 0)], "blue": [(0, 0)]},
}

SIGMA_PX = 0.5  # Gaussian blur of the rendered edge (px of the full array)
TILT_DEG = 5.0  # edge from the y axis (a near-vertical edge: the ACT MTF)


def _psi(z):
    """Second antiderivative of the standard normal CDF: psi'' = Phi."""
    return 0.5 * ((z * z + 1.0) * ndtr(z) + z * np.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi))


def render_edge(x, y, *, tilt_deg=TILT_DEG, sigma=SIGMA_PX, width=1.0, x0=0.0, lo=0.2, hi=0.8):
    """An edge through (x0, 0) tilted ``tilt_deg`` from the y axis, bright on +x, blurred by a Gaussian of
    ``sigma`` and integrated over a square photosite of ``width`` centred at each (x, y) (px): exactly, as
    the second difference of psi over the photosite's projection on the edge normal (two boxes, of widths
    width |cos t| and width |sin t|). Its OTF along the normal: exp(-2 pi^2 sigma^2 f^2) sinc(w fx) sinc(w fy)."""
    t = math.radians(tilt_deg)
    d = (np.asarray(x, float) - x0) * math.cos(t) - np.asarray(y, float) * math.sin(t)
    a, b = width * abs(math.cos(t)), width * abs(math.sin(t))
    F = lambda u: sigma**2 * _psi(u / sigma)  # noqa: E731
    step = (F(d + a / 2 + b / 2) - F(d + a / 2 - b / 2) - F(d - a / 2 + b / 2) + F(d - a / 2 - b / 2)) / (a * b)
    return lo + (hi - lo) * step


def true_mtf(f_cy_per_px, tilt_deg=TILT_DEG, sigma=SIGMA_PX, width=1.0):
    """The rendered edge's MTF along its normal at ``f`` cy/px of the full array (the Gaussian times the
    photosite's sinc along x and y)."""
    t = math.radians(tilt_deg)
    fx, fy = f_cy_per_px * math.cos(t), f_cy_per_px * math.sin(t)
    return np.exp(-2 * math.pi**2 * sigma**2 * f_cy_per_px**2) * np.sinc(width * fx) * np.sinc(width * fy)


def _otf_cy_per_mm(pitch_mm):
    """The rendered edge's OTF as the callable of cy/mm that satchain.tf.cfa takes (a system with this pitch)."""

    def otf(fx, fy):
        fx_px, fy_px = np.asarray(fx) * pitch_mm, np.asarray(fy) * pitch_mm
        g = np.exp(-2 * math.pi**2 * SIGMA_PX**2 * (fx_px**2 + fy_px**2))
        return g * np.sinc(fx_px) * np.sinc(fy_px)

    return otf


def test_the_rendered_edge_is_an_edge():
    x = np.linspace(-20, 20, 401)
    e = render_edge(x, 0 * x)
    assert e[0] == pytest.approx(0.2, abs=1e-9) and e[-1] == pytest.approx(0.8, abs=1e-9)
    assert np.all(np.diff(e) >= -1e-12)
    # a photosite of zero width is the Gaussian edge itself
    assert render_edge(1.0, 0.0, width=1e-3) == pytest.approx(
        0.2 + 0.6 * ndtr(math.cos(math.radians(5)) / 0.5), abs=1e-5
    )


# ------------------------------------------------------------------ the mosaic keeps the right photosites


@pytest.mark.parametrize("pattern", PATTERNS)
def test_mosaic_keeps_each_colours_photosites(pattern):
    rows, cols = 6, 8
    rng = np.random.default_rng(3)
    rgb = rng.uniform(0.0, 1.0, (rows, cols, 3))
    raw = mosaic(rgb, pattern)
    counts = {}
    for k, colour in enumerate(("red", "green", "blue")):
        expect = np.zeros((rows, cols), dtype=bool)
        for r0, c0 in SITES[pattern][colour]:
            expect[r0::2, c0::2] = True
        np.testing.assert_array_equal(raw[expect], rgb[..., k][expect])
        np.testing.assert_array_equal(cfa_masks((rows, cols), pattern)[colour], expect)
        counts[colour] = int(expect.sum())
    assert counts == {"red": rows * cols // 4, "green": rows * cols // 2, "blue": rows * cols // 4}


def test_mosaic_takes_a_mapping_or_a_callable_and_a_window_keeps_the_phase():
    rng = np.random.default_rng(5)
    rgb = rng.uniform(0.0, 1.0, (8, 10, 3))
    planes = {c: rgb[..., k] for k, c in enumerate(("red", "green", "blue"))}
    full = mosaic(rgb, "GRBG")
    np.testing.assert_array_equal(mosaic(planes, "GRBG"), full)
    np.testing.assert_array_equal(mosaic(planes.__getitem__, "GRBG"), full)
    # a window at an odd offset is the crop of the full mosaic (tiled == untiled)
    np.testing.assert_array_equal(mosaic(rgb[3:7, 1:8], "GRBG", origin=(3, 1)), full[3:7, 1:8])


def test_mosaic_and_demosaic_refuse_bad_input():
    with pytest.raises(Exception, match=r"cfa pattern = 'RGBG': must be one of 'RGGB', 'GRBG', 'GBRG', 'BGGR'"):
        mosaic(np.zeros((4, 4, 3)), "RGBG")
    with pytest.raises(Exception, match=r"method = 'nearest': must be one of 'bilinear', 'malvar2004', 'menon2007'"):
        demosaic(np.zeros((4, 4)), "RGGB", method="nearest")
    with pytest.raises(InputError, match=r"planes has shape \(4, 4, 2\)"):
        mosaic(np.zeros((4, 4, 2)), "RGGB")
    with pytest.raises(InputError, match="the green plane has shape"):
        mosaic({"red": np.zeros((4, 4)), "green": np.zeros((4, 5)), "blue": np.zeros((4, 4))}, "RGGB")


# ------------------------------------------------------------------ round trips


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("pattern", PATTERNS)
def test_a_uniform_grey_scene_comes_back_exactly_grey(pattern, method):
    rgb = np.full((12, 14, 3), 0.37)
    out = demosaic(mosaic(rgb, pattern), pattern, method=method)
    np.testing.assert_allclose(out, rgb, rtol=1e-12, atol=0)
    assert false_colour_amplitude(out).peak == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_a_uniform_colour_has_no_false_colour(method):
    colour = np.array([0.3, 0.5, 0.2])
    rgb = np.ones((12, 12, 1)) * colour
    out = demosaic(mosaic(rgb, "RGGB"), "RGGB", method=method)
    np.testing.assert_allclose(out, rgb, rtol=1e-12, atol=1e-15)
    assert false_colour_amplitude(out, reference=colour).peak == pytest.approx(0.0, abs=1e-12)
    assert false_colour_amplitude(out).peak > 0.1  # measured against neutral, the colour itself is chroma


# ------------------------------------------------------------------ each colour plane's MTF on its own grid


#: The edge is straight and still: the planes are measured with ISO 12233's straight fit (fit_degree=1). On a
#: plane this undersampled (its MTF at its Nyquist is 0.66) the per-line edge positions of some phases wobble
#: with the aliasing, which measure_edge's "auto" reads as line-of-sight motion (flag line_of_sight_motion) and
#: corrects, reading the MTF at Nyquist 0.046 low (red at x0 = 80.55 px, blue at 80.3 px).
_STRAIGHT = 1


def _measured_at(res, f_cy_per_px_plane):
    return float(np.interp(f_cy_per_px_plane, res.f_cy_per_px, res.mtf))


@pytest.mark.parametrize("pattern", PATTERNS)
@pytest.mark.parametrize("colour", ["red", "blue"])
def test_red_and_blue_plane_mtf_at_their_nyquist(pattern, colour):
    """Red and blue: a rectangular lattice of pitch 2 px; the plane's own grid is every second photosite."""
    (r0, c0) = SITES[pattern][colour][0]
    n = 160
    y, x = np.mgrid[0:n, 0:n].astype(float)
    raw = mosaic(np.repeat(render_edge(x, y, x0=n / 2 + 0.3)[..., None], 3, axis=2), pattern)
    plane = raw[r0::2, c0::2]
    res = measure_edge(plane, f_max_cy_per_px=1.0, fit_degree=_STRAIGHT)
    assert res.direction == "ACT" and abs(abs(res.angle_deg) - TILT_DEG) < 0.05
    p_mm = 5e-3
    otf = _otf_cy_per_mm(p_mm)
    # at the plane grid's Nyquist (0.5 cy per plane pixel = 0.25 cy/px), along the edge normal
    f_n = grid_nyquist_cy_per_px(colour)
    predicted = float(plane_mtf(otf, f_n, pitch_x_m=p_mm * 1e-3, pitch_y_m=p_mm * 1e-3, direction_deg=-TILT_DEG))
    assert predicted == pytest.approx(float(true_mtf(f_n)), abs=1e-12)
    assert res.mtf_at_nyquist == pytest.approx(predicted, abs=0.02)
    # and where the ray along the normal leaves the plane's Brillouin zone (0.25 / cos 5 deg)
    f_z = nyquist_cy_per_px(pattern, colour, direction_deg=-TILT_DEG)
    assert f_z == pytest.approx(0.25 / math.cos(math.radians(TILT_DEG)), rel=1e-12)
    assert _measured_at(res, 2 * f_z) == pytest.approx(float(true_mtf(f_z)), abs=0.02)


def _green_plane(pattern, n):
    """The green quincunx on its own square grid of pitch sqrt(2) px (turned by 45 deg): plane[i, j] is the
    photosite at column c = i + j + c0, row r = i - j + r0 (r0, c0: a green site of the cell)."""
    r0, c0 = SITES[pattern]["green"][0]
    i, j = np.mgrid[0:n, 0:n]
    c, r = i + j + c0, i - j + r0 + n
    y, x = np.mgrid[0 : 2 * n + 2, 0 : 2 * n + 2].astype(float)
    raw = mosaic(np.repeat(render_edge(x, y, x0=n + 0.3)[..., None], 3, axis=2), pattern)
    assert cfa_masks(raw.shape, pattern)["green"][r, c].all()
    return raw[r, c]


@pytest.mark.parametrize("pattern", PATTERNS)
def test_green_plane_mtf_at_its_nyquist(pattern):
    plane = _green_plane(pattern, 96)
    res = measure_edge(plane, f_max_cy_per_px=1.0, fit_degree=_STRAIGHT)
    # on the turned grid the edge normal (5 deg from x) is 40 deg from the plane's rows; frequencies are per
    # plane pixel of sqrt(2) px
    to_plane = math.sqrt(2.0)
    f_n = grid_nyquist_cy_per_px("green")
    assert f_n == pytest.approx(0.5 / to_plane, rel=1e-12)
    assert res.mtf_at_nyquist == pytest.approx(float(true_mtf(f_n)), abs=0.02)
    # along ACT the quincunx's zone reaches 1/(2p): read there too (0.5 cy/px = 0.707 cy per plane pixel)
    f_z = nyquist_cy_per_px(pattern, "green", direction_deg=-TILT_DEG)
    assert _measured_at(res, f_z * to_plane) == pytest.approx(float(true_mtf(f_z)), abs=0.02)


# ------------------------------------------------------------------ false colour at a neutral edge


def _neutral_edge_rgb(pattern, method, n=96, sigma=0.35):
    y, x = np.mgrid[0:n, 0:n].astype(float)
    grey = render_edge(x, y, x0=n / 2 + 0.3, sigma=sigma)
    out = demosaic(mosaic(np.repeat(grey[..., None], 3, axis=2), pattern), pattern, method=method)
    t = math.radians(TILT_DEG)
    near = np.abs((x - n / 2 - 0.3) * math.cos(t) - y * math.sin(t)) < 4.0
    near[:4], near[-4:], near[:, :4], near[:, -4:] = False, False, False, False
    return out, near


def cfa_edge_figures(pattern="RGGB"):
    """{method: (MTF50 of the demosaiced luminance in cy/px, false colour peak, rms)} at a neutral 5 deg edge."""
    out = {}
    for method in METHODS:
        rgb, near = _neutral_edge_rgb(pattern, method)
        res = measure_edge(luminance(rgb)[4:-4, 4:-4])
        fc = false_colour_amplitude(rgb, valid=near)
        out[method] = (res.mtf50_cy_per_px, fc.peak, fc.rms)
    return out


def test_a_sharp_neutral_edge_shows_false_colour_bilinear_most():
    figures = cfa_edge_figures()
    for method, (mtf50, peak, rms) in figures.items():
        assert peak > 1e-3 and rms > 0.0, method
        assert mtf50 is not None and 0.1 < mtf50 < 0.6, method
    assert figures["bilinear"][1] > figures["malvar2004"][1]
    assert figures["bilinear"][1] > figures["menon2007"][1]
    assert figures["bilinear"][2] > figures["malvar2004"][2]
    assert figures["bilinear"][2] > figures["menon2007"][2]


def test_false_colour_refuses_an_empty_region():
    with pytest.raises(InputError, match="no pixel"):
        false_colour_amplitude(np.ones((4, 4, 3)), valid=np.zeros((4, 4), dtype=bool))


def test_demosaicing_leaves_numpy_printing_as_it_was():
    """colour-science switches numpy to its 1.13 print style when imported: demosaic puts the caller's back."""
    from satchain.engine.cfa import demosaic, mosaic

    before = np.get_printoptions()
    planes = {c: np.full((8, 8), 0.5) for c in ("red", "green", "blue")}
    demosaic(mosaic(planes, "RGGB"), "RGGB", method="bilinear")
    assert np.get_printoptions() == before
    assert repr(np.array([0.5, 0.0])) == "array([0.5, 0. ])"
