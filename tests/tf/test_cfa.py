"""Issue 32, point 4: the sampling of a Bayer colour filter array (satchain.tf.cfa), against closed forms.

The alias positions of each colour plane are the frequencies where the DFT of that colour's site indicator (the
pattern written out here, tiled) is nonzero, and each DFT coefficient's phase is the replica phase of the plane's
origin; the Nyquist frequency along any direction is the closed-form boundary of the first Brillouin zone
(a square |f| <= 1/4 per axis for red and blue, a diamond |fx| + |fy| <= 1/2 for green); a colour plane's MTF at
its Nyquist is the system MTF evaluated there; a pattern's phase moves the lattice and changes no MTF.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain import load_preset
from satchain.errors import ConfigError
from satchain.tf.budget import SystemOTF, mtf_at_nyquist
from satchain.tf.cfa import (
    alias_frequencies_cy_per_px,
    aliased_fraction,
    cfa_sites,
    first_alias_cy_per_px,
    grid_nyquist_cy_per_px,
    in_passband,
    nyquist_cy_per_px,
    plane_lattice,
    plane_mtf,
    plane_mtf_at_nyquist,
)

PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")
COLOURS = ("red", "green", "blue")
LETTER = {"red": "R", "green": "G", "blue": "B"}


def _indicator(pattern: str, colour: str, n: int = 8) -> np.ndarray:
    """1 at the colour's photosites of an n x n array, from the pattern's letters (row by row)."""
    cell = np.array([[pattern[0], pattern[1]], [pattern[2], pattern[3]]])
    return (np.tile(cell, (n // 2, n // 2)) == LETTER[colour]).astype(float)


def _wrap(f):
    """Frequencies (cy/px) folded into [-1/2, 1/2): where a DFT of a pixel grid sees them."""
    return (np.asarray(f) + 0.5) % 1.0 - 0.5


@pytest.mark.parametrize("pattern", PATTERNS)
@pytest.mark.parametrize("colour", COLOURS)
def test_alias_positions_are_the_spectrum_of_the_sampling_comb(pattern, colour):
    n = 8
    ind = _indicator(pattern, colour, n)
    spec = np.fft.fft2(ind) / ind.sum()  # [ky, kx]: the comb's spectrum, 1 at f = 0
    f = np.fft.fftfreq(n)
    nonzero = {
        (round(float(f[kx]), 9), round(float(f[ky]), 9))
        for ky, kx in zip(*np.nonzero(np.abs(spec) > 1e-9), strict=True)
    }
    g = alias_frequencies_cy_per_px(pattern, colour, f_max_cy_per_px=1.0)
    predicted = {(round(float(a), 9), round(float(b), 9)) for a, b in _wrap(g)} | {(0.0, 0.0)}
    predicted = {(0.0 if a == -0.0 else a, 0.0 if b == -0.0 else b) for a, b in predicted}
    assert nonzero == predicted
    # each replica's weight is exp(-2 pi i g . origin): the comb's DFT at g (numpy's sign convention)
    lat = plane_lattice(pattern, colour)
    for gx, gy in g:
        kx, ky = int(round(gx * n)) % n, int(round(gy * n)) % n
        assert spec[ky, kx] == pytest.approx(complex(lat.replica_phase([gx, gy])), abs=1e-12)


@pytest.mark.parametrize("pattern", PATTERNS)
def test_the_reciprocal_lattices_in_closed_form(pattern):
    red = alias_frequencies_cy_per_px(pattern, "red", f_max_cy_per_px=1.0)
    green = alias_frequencies_cy_per_px(pattern, "green", f_max_cy_per_px=1.0)
    half = np.arange(-2, 3) / 2.0
    rect = {(a, b) for a in half for b in half if (a, b) != (0, 0)}
    assert {tuple(map(float, p)) for p in red} == rect
    # the quincunx: (m + n, m - n) / 2, i.e. half-integer pairs whose sum is an integer
    assert {tuple(map(float, p)) for p in green} == {(a, b) for a, b in rect if float(a + b).is_integer()}
    np.testing.assert_array_equal(
        alias_frequencies_cy_per_px(pattern, "blue"), alias_frequencies_cy_per_px(pattern, "red")
    )
    assert [plane_lattice(pattern, c).sites_per_pixel for c in COLOURS] == [0.25, 0.5, 0.25]
    # nearest first: red's nearest alias at 1/2 cy/px (its sampling frequency), green's at 1/sqrt(2)
    assert np.hypot(*red[0]) == pytest.approx(0.5) and np.hypot(*green[0]) == pytest.approx(math.sqrt(0.5))


@settings(max_examples=60, deadline=None)
@given(st.floats(-180.0, 180.0), st.sampled_from(PATTERNS))
def test_nyquist_along_any_direction_is_the_zone_boundary(direction_deg, pattern):
    a = math.radians(direction_deg)
    c, s = abs(math.cos(a)), abs(math.sin(a))
    assert nyquist_cy_per_px(pattern, "red", direction_deg=direction_deg) == pytest.approx(0.25 / max(c, s))
    assert nyquist_cy_per_px(pattern, "blue", direction_deg=direction_deg) == pytest.approx(0.25 / max(c, s))
    assert nyquist_cy_per_px(pattern, "green", direction_deg=direction_deg) == pytest.approx(0.5 / (c + s))
    for colour in COLOURS:
        f = nyquist_cy_per_px(pattern, colour, direction_deg=direction_deg)
        u = np.array([math.cos(a), math.sin(a)])
        assert in_passband(*(0.999 * f * u), pattern, colour)
        assert not in_passband(*(1.001 * f * u), pattern, colour)


def test_the_nyquist_values_the_issue_names():
    assert nyquist_cy_per_px("RGGB", "red", direction_deg=0.0) == 0.25  # 1/(4p) per axis
    assert nyquist_cy_per_px("RGGB", "blue", direction_deg=90.0) == 0.25
    assert nyquist_cy_per_px("RGGB", "green", direction_deg=0.0) == pytest.approx(0.5)  # 1/(2p) along the axes
    assert nyquist_cy_per_px("RGGB", "green", direction_deg=45.0) == pytest.approx(1 / (2 * math.sqrt(2)))
    assert grid_nyquist_cy_per_px("red") == 0.25 and grid_nyquist_cy_per_px("green") == pytest.approx(0.3535534)


@settings(max_examples=80, deadline=None)
@given(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0), st.sampled_from(PATTERNS), st.sampled_from(COLOURS))
def test_the_first_alias_is_in_the_passband_a_lattice_step_away(fx, fy, pattern, colour):
    ax, ay = first_alias_cy_per_px(fx, fy, pattern, colour)
    assert in_passband(ax, ay, pattern, colour)
    # f - alias is a reciprocal-lattice point: integer coordinates on the reciprocal basis
    k = np.array([fx - ax, fy - ay]) @ plane_lattice(pattern, colour).basis_px.T
    np.testing.assert_allclose(k, np.rint(k), atol=1e-9)
    if in_passband(fx, fy, pattern, colour):
        assert (float(ax), float(ay)) == pytest.approx((fx, fy))


def test_first_alias_examples():
    # 0.3 cy/px along x: beyond red's 0.25, it folds to 0.3 - 0.5; within green's 0.5, it stays
    assert [float(v) for v in first_alias_cy_per_px(0.3, 0.0, "RGGB", "red")] == pytest.approx([-0.2, 0.0])
    assert [float(v) for v in first_alias_cy_per_px(0.3, 0.0, "RGGB", "green")] == pytest.approx([0.3, 0.0])
    # 0.3 cy/px along the diagonal (|f| = 0.42 > 0.354): green folds it by (1/2, 1/2)
    assert [float(v) for v in first_alias_cy_per_px(0.3, 0.3, "GRBG", "green")] == pytest.approx([-0.2, -0.2])


def test_the_aliased_fraction():
    f = np.linspace(0.0, 1.0, 201)
    fx, fy = np.meshgrid(f, f)
    band_limited = np.where(np.hypot(fx, fy) < 0.2, 1.0, 0.0)
    for colour in COLOURS:
        assert aliased_fraction(fx, fy, band_limited, "RGGB", colour) == 0.0
    sinc = np.abs(np.sinc(fx) * np.sinc(fy))  # the photosite aperture alone
    red, green = (aliased_fraction(fx, fy, sinc, "RGGB", c) for c in ("red", "green"))
    assert 0 < green < red < 1
    # a uniform cut along x of a triangle MTF: the part beyond 1/4 is (3/4)^2 of its area (discretised)
    tri = 1.0 - f
    expected = np.sum(tri[f > 0.25 + 1e-12]) / np.sum(tri)
    assert aliased_fraction(f, 0.0, tri, "BGGR", "blue") == pytest.approx(expected, rel=1e-12)
    assert expected == pytest.approx(0.75**2, abs=0.01)


# ------------------------------------------------------------------ the plane MTF from the system OTF


@pytest.fixture(scope="module")
def paper():
    system = load_preset("ankarasat3")
    return system, SystemOTF(system)


def test_plane_mtf_at_nyquist_is_the_system_mtf_there(paper):
    system, otf = paper
    p = system.detector.pitch_x_m
    kw = dict(pitch_x_m=p, pitch_y_m=system.detector.pitch_y_m)
    f_red_cy_per_mm = 1.0 / (4.0 * p * 1e3)  # 1/(4p): 42.517 cy/mm for 5.88 um
    assert f_red_cy_per_mm == pytest.approx(42.517, abs=1e-3)
    for pattern in PATTERNS:
        for colour in ("red", "blue"):
            assert plane_mtf_at_nyquist(otf, pattern, colour, **kw) == pytest.approx(abs(otf(f_red_cy_per_mm, 0.0)))
            alt = plane_mtf_at_nyquist(otf, pattern, colour, direction_deg=90.0, **kw)
            assert alt == pytest.approx(abs(otf(0.0, f_red_cy_per_mm)))
        # green along the axes reaches the array's own Nyquist: the monochrome budget's MTF at Nyquist
        mono = mtf_at_nyquist(system, otf=otf)
        assert plane_mtf_at_nyquist(otf, pattern, "green", **kw) == pytest.approx(mono["act"], abs=1e-9)
        assert plane_mtf_at_nyquist(otf, pattern, "green", direction_deg=90.0, **kw) == pytest.approx(
            mono["alt"], abs=1e-9
        )
        f_diag = 1.0 / (2.0 * math.sqrt(2.0) * p * 1e3) / math.sqrt(2.0)  # 1/(2 sqrt 2 p) along 45 deg: each axis
        assert plane_mtf_at_nyquist(otf, pattern, "green", direction_deg=45.0, **kw) == pytest.approx(
            abs(otf(f_diag, f_diag))
        )
    assert plane_mtf(otf, 0.0, **kw) == pytest.approx(1.0)


def test_a_patterns_phase_moves_the_lattice_and_changes_no_mtf(paper):
    system, otf = paper
    kw = dict(pitch_x_m=system.detector.pitch_x_m, pitch_y_m=system.detector.pitch_y_m)
    a, b = plane_lattice("RGGB", "red"), plane_lattice("BGGR", "red")
    np.testing.assert_array_equal(b.origin_px - a.origin_px, [1.0, 1.0])  # one pixel diagonally
    np.testing.assert_array_equal(a.basis_px, b.basis_px)
    np.testing.assert_array_equal(
        alias_frequencies_cy_per_px("RGGB", "red"), alias_frequencies_cy_per_px("BGGR", "red")
    )
    for d in (0.0, 30.0, 90.0):
        m_a = plane_mtf_at_nyquist(otf, "RGGB", "red", direction_deg=d, **kw)
        assert plane_mtf_at_nyquist(otf, "BGGR", "red", direction_deg=d, **kw) == m_a
    # the replicas' weights differ only in sign (phase pi at (1/2, 0), 0 at (1/2, 1/2)), never in modulus
    g = alias_frequencies_cy_per_px("RGGB", "red", f_max_cy_per_px=0.5)
    np.testing.assert_allclose(np.abs(b.replica_phase(g)), np.abs(a.replica_phase(g)))
    assert b.replica_phase([0.5, 0.0]) == pytest.approx(-a.replica_phase([0.5, 0.0]))
    assert b.replica_phase([0.5, 0.5]) == pytest.approx(a.replica_phase([0.5, 0.5]))


def test_cfa_sites_and_bad_input():
    assert cfa_sites("GBRG", "blue") == ((0, 1),) and cfa_sites("GBRG", "green") == ((0, 0), (1, 1))
    with pytest.raises(ConfigError, match=r"cfa pattern = 'RGBG': must be one of 'RGGB', 'GRBG', 'GBRG', 'BGGR'"):
        nyquist_cy_per_px("RGBG", "red")
    with pytest.raises(ConfigError, match=r"colour = 'cyan': must be one of 'red', 'green', 'blue'"):
        plane_lattice("RGGB", "cyan")


def test_detector_cfa_config():
    """[detector] cfa: None by default (today's monochrome array), one of the four patterns, or refused naming
    the value and the list; its responses default to the packaged ones."""
    from satchain.config.sections_cfa import cfa_response

    s = load_preset("ankarasat3")
    assert s.detector.cfa is None and "cfa" not in s.to_dict()["detector"]
    for pattern in PATTERNS:
        assert s.replace({"detector.cfa": pattern}).detector.cfa == pattern
    with pytest.raises(ConfigError, match=r"detector\.cfa = 'RGBG': input should be 'RGGB', 'GRBG', 'GBRG' or 'BGGR'"):
        s.replace({"detector.cfa": "RGBG"})
    with pytest.raises(ConfigError, match=r"detector\.cfa_responses is given but detector\.cfa is not"):
        s.replace({"detector.cfa_responses": {"red": {"center_m": 6e-7, "fwhm_m": 1e-7}}})
    rggb = s.replace({"detector.cfa": "RGGB"})
    peaks = {c: cfa_response(rggb.detector, c) for c in COLOURS}
    lam = np.arange(380e-9, 781e-9, 5e-9)
    centroids = {c: float(np.sum(lam * r.at(lam)) / np.sum(r.at(lam))) for c, r in peaks.items()}
    assert centroids["blue"] < centroids["green"] < centroids["red"]
    assert 440e-9 < centroids["blue"] < 500e-9 and 500e-9 < centroids["green"] < 560e-9 and centroids["red"] > 570e-9
    mine = s.replace({"detector.cfa": "RGGB", "detector.cfa_responses": {"red": {"center_m": 6.5e-7, "fwhm_m": 1e-7}}})
    assert float(cfa_response(mine.detector, "red").at(7.0e-7)) == pytest.approx(0.5)
    assert cfa_response(mine.detector, "green") == peaks["green"]


def test_a_colours_system_sees_the_world_through_its_filter():
    """colour_system: the optics' wavelengths and weights keep the response's centroid, the QE is the detector's
    times the response, and a longer-wavelength colour has the lower diffraction MTF (a circular pupil)."""
    from importlib import resources

    from satchain.config.sections_cfa import colour_system

    s = load_preset("ankarasat3").replace({"detector.cfa": "GRBG", "optics.obscuration_ratio": 0.0})
    table = np.loadtxt(
        str(resources.files("satchain") / "data" / "cfa" / "nikon_d5100_npl.csv"), delimiter=",", skiprows=1
    )
    fine = np.linspace(380.0, 780.0, 400_001)
    diffraction = {}
    for k, colour in enumerate(COLOURS):
        c = colour_system(s, colour)
        r = np.interp(fine, table[:, 0], table[:, k + 1])
        centroid_nm = float(np.sum(fine * r) / np.sum(r))
        assert c.optics.effective_wavelength_m * 1e9 == pytest.approx(centroid_nm, abs=0.05)
        assert c.radiometry.band_m == pytest.approx((380e-9, 780e-9))
        for lam_nm in (450.0, 530.0, 600.0, 655.5):
            want = 0.6 * np.interp(lam_nm, table[:, 0], table[:, k + 1])  # the preset's QE 0.6 x the response
            assert float(c.detector.qe_at(lam_nm * 1e-9)) == pytest.approx(want, abs=1e-12)
        assert c.detector.cfa == "GRBG" and c.optics.focal_length_m == s.optics.focal_length_m
        diffraction[colour] = abs(SystemOTF(c).components(85.034, 0.0)["diffraction"])
    assert diffraction["red"] < diffraction["green"] < diffraction["blue"]
    with pytest.raises(ConfigError, match=r"colour = 'red': detector\.cfa is not set"):
        colour_system(load_preset("ankarasat3"), "red")


def test_a_cfa_pattern_not_in_the_list_is_one_line_and_exit_2(tmp_path):
    from typer.testing import CliRunner

    from satchain.cli.main import app

    system = """[orbit]
altitude_m = 500000
[optics]
aperture_diameter_m = 0.5
focal_length_m = 5.0
wavelengths_m = [6.5e-7]
[detector]
pitch_m = 5e-6
cfa = "{}"
"""
    bad, good = tmp_path / "bad.toml", tmp_path / "good.toml"
    bad.write_text(system.format("RGBG"))
    good.write_text(system.format("BGGR"))
    result = CliRunner().invoke(app, ["budget", "--system", str(bad), "--json"])
    assert result.exit_code == 2
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert lines == [
        "error: invalid imaging system: detector.cfa = 'RGBG': input should be 'RGGB', 'GRBG', 'GBRG' or 'BGGR'"
    ]
    assert CliRunner().invoke(app, ["budget", "--system", str(good), "--json"]).exit_code == 0
