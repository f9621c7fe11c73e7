"""Issue 32 point 4: the budget of a Bayer colour camera predicts each colour plane's MTF on its own sampling grid
(red and blue at 2x the pitch, green in quincunx) and where each aliases (satchain.prediction.cfa_budget, the
block ``cfa`` of ``satchain budget`` text and --json and of ``satchain.budget(system)``).

A camera with narrow (1 nm) Gaussian colour responses is monochromatic per colour: its planes' MTFs are the closed
forms of an unobscured circular pupil's diffraction MTF at the colour's wavelength times the square pixel's sinc.
Where each plane aliases is checked by sampling a cosine on the colour's own photosites."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import satchain
from satchain.cli.main import app
from satchain.tf.cfa import cfa_sites

PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")
COLOURS = ("red", "green", "blue")
CENTRE_M = {"red": 620e-9, "green": 540e-9, "blue": 460e-9}
PITCH_M, F_NUMBER = 5e-6, 10.0


def _system(pattern: str = "RGGB", *, narrow: bool = True) -> satchain.ImagingSystem:
    det: dict = {"pitch_m": PITCH_M, "cfa": pattern}
    if narrow:
        det["cfa_responses"] = {c: {"center_m": CENTRE_M[c], "fwhm_m": 1e-9} for c in COLOURS}
    optics = {"aperture_diameter_m": 0.5, "f_number": F_NUMBER, "wavelengths_m": [6e-7]}
    return satchain.ImagingSystem.from_dict(
        {"name": "bayer", "orbit": {"altitude_m": 500e3}, "detector": det, "optics": optics}
    )


def _closed_form(colour: str, f_cy_per_px: float, direction_deg: float) -> float:
    """Diffraction MTF of a circular pupil (2/pi (acos x - x sqrt(1 - x^2)), x = nu lambda F#) x sinc x sinc."""
    a = math.radians(direction_deg)
    x = f_cy_per_px / PITCH_M * CENTRE_M[colour] * F_NUMBER
    diff = 2 / math.pi * (math.acos(x) - x * math.sqrt(1 - x * x)) if x < 1 else 0.0
    return diff * abs(np.sinc(f_cy_per_px * math.cos(a)) * np.sinc(f_cy_per_px * math.sin(a)))


@pytest.fixture(scope="module")
def block():
    return satchain.budget(_system()).to_dict()["cfa"]


def test_each_plane_at_its_own_nyquist_is_the_closed_form(block):
    ny = {"red": (0.25, 0.25, math.sqrt(2) / 4), "green": (0.5, 0.5, 1 / (2 * math.sqrt(2))),
          "blue": (0.25, 0.25, math.sqrt(2) / 4)}  # fmt: skip
    for c in COLOURS:
        p = block["planes"][c]
        for (d, a), f in zip({"act": 0.0, "alt": 90.0, "diagonal": 45.0}.items(), ny[c], strict=True):
            assert p["nyquist_cy_per_px"][d] == pytest.approx(f, rel=1e-12), (c, d)
            assert p["mtf_at_nyquist"][d] == pytest.approx(_closed_form(c, f, a), abs=2e-4), (c, d)
        assert p["nyquist_cy_per_mm"]["act"] == pytest.approx(ny[c][0] / (PITCH_M * 1e3))
        grid = 0.25 if c != "green" else 1 / (2 * math.sqrt(2))  # the plane's own grid: 2 px, or sqrt(2) px
        assert p["grid_nyquist_cy_per_px"] == pytest.approx(grid)
        assert p["mtf_at_grid_nyquist"]["act"] == pytest.approx(_closed_form(c, grid, 0.0), abs=2e-4)
        assert p["effective_wavelength_m"] == pytest.approx(CENTRE_M[c], rel=1e-3)
    # sampled twice as coarsely, red and blue keep more MTF at their Nyquist than green at its own
    assert block["planes"]["blue"]["mtf_at_nyquist"]["act"] > block["planes"]["green"]["mtf_at_nyquist"]["act"]
    assert block["responses"]["red"].startswith("system file: Gaussian, centre 620.0 nm")
    assert block["pattern"] == "RGGB"


def test_the_fraction_beyond_nyquist(block):
    # red's zone (a 0.5 cy/px square) holds less of its MTF than green's diamond (twice its area) holds of green's
    red, green = block["planes"]["red"]["aliased_fraction"], block["planes"]["green"]["aliased_fraction"]
    assert 0.0 < green < red < 1.0
    # a system whose optics cut off inside red's zone (Q = lambda F# / p >= 4) does not alias at all
    s = _system().replace({"optics.f_number": 40.0})
    assert satchain.budget(s).to_dict()["cfa"]["planes"]["red"]["aliased_fraction"] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("pattern", PATTERNS)
def test_where_each_plane_aliases_a_cosine_sampled_on_its_photosites(pattern):
    """A cosine at the plane's alias frequency along a direction reads the same value at every photosite of the
    colour (it aliases to zero frequency); just below that frequency it does not."""
    planes = satchain.budget(_system(pattern)).to_dict()["cfa"]["planes"]
    rows, cols = np.mgrid[0:16, 0:16]
    for c in COLOURS:
        sites = np.zeros((16, 16), bool)
        for r, k in cfa_sites(pattern, c):
            sites[r::2, k::2] = True
        y, x = rows[sites], cols[sites]
        for d, a in {"act": 0.0, "alt": 90.0, "diagonal": 45.0}.items():
            f = planes[c]["alias_cy_per_px"][d]
            assert f == pytest.approx(2 * planes[c]["nyquist_cy_per_px"][d])  # along a lattice vector: 2 Nyquist
            u = (math.cos(math.radians(a)), math.sin(math.radians(a)))
            phase = 2 * np.pi * f * (x * u[0] + y * u[1])
            assert np.ptp(np.cos(phase)) < 1e-9, (c, d)
            assert np.ptp(np.cos(phase * 0.9)) > 0.1, (c, d)
    red = np.asarray(planes["red"]["first_alias_points_cy_per_px"])
    assert sorted(map(tuple, np.abs(red).tolist())) == [(0.0, 0.5), (0.0, 0.5), (0.5, 0.0), (0.5, 0.0)]
    green = np.abs(np.asarray(planes["green"]["first_alias_points_cy_per_px"]))
    assert green.shape == (4, 2) and np.allclose(green, 0.5)


def test_every_pattern_gives_the_same_plane_mtfs():
    ref = satchain.budget(_system()).to_dict()["cfa"]["planes"]
    for pattern in PATTERNS[1:]:
        got = satchain.budget(_system(pattern)).to_dict()["cfa"]["planes"]
        for c in COLOURS:
            assert got[c]["mtf_at_nyquist"] == pytest.approx(ref[c]["mtf_at_nyquist"], abs=1e-12)


def test_typed_budget_and_a_monochrome_system_unchanged(block):
    b = satchain.budget(_system())
    assert b.cfa is not None and b.cfa.pattern == "RGGB"
    assert b.cfa.planes["green"].mtf_at_nyquist["act"] == block["planes"]["green"]["mtf_at_nyquist"]["act"]
    assert b.cfa.planes["red"].nyquist_cy_per_px["diagonal"] == pytest.approx(math.sqrt(2) / 4)
    mono = satchain.budget(_system(narrow=False).replace({"detector.cfa": None}))
    assert mono.cfa is None and "cfa" not in mono.to_dict()
    # the packaged responses by default, with their source
    default = satchain.budget(_system(narrow=False)).cfa
    assert default is not None and all(s.startswith("packaged default") for s in default.responses.values())


def test_cli_budget_text_and_json(tmp_path, minimal_system_toml):
    f = tmp_path / "s.toml"
    f.write_text(minimal_system_toml.replace("[detector]\n", '[detector]\ncfa = "GRBG"\n'))
    text = CliRunner().invoke(app, ["budget", "--system", str(f)], env={"COLUMNS": "200"})
    assert text.exit_code == 0, text.output
    assert "colour filter array GRBG" in text.output and "quincunx" in text.output
    assert "packaged default" in text.output
    data = json.loads(CliRunner().invoke(app, ["budget", "--system", str(f), "--json"]).stdout)
    planes = data["cfa"]["planes"]
    assert set(planes) == set(COLOURS) and planes["green"]["nyquist_cy_per_mm"]["act"] == pytest.approx(100.0)
    assert planes["red"]["sites_rc"] == [[0, 1]]
    plain = tmp_path / "p.toml"
    plain.write_text(minimal_system_toml)
    out = json.loads(CliRunner().invoke(app, ["budget", "--system", str(plain), "--json"]).stdout)
    assert "cfa" not in out
    bad = tmp_path / "b.toml"
    bad.write_text(minimal_system_toml.replace("[detector]\n", '[detector]\ncfa = "RGBG"\n'))
    res = CliRunner().invoke(app, ["budget", "--system", str(bad)])
    assert res.exit_code == 2 and "cfa" in res.output
