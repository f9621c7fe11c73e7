"""Issue 32 point 4 in ``satchain run``: a Bayer camera's raw mosaic, each raw colour plane's MTF on its own grid
against its prediction, and the three demosaicing methods side by side (satchain.focal.cfa, report.focal_cfa).

One noise-free run (``satchain run`` on the command line) of a camera whose colour responses are narrow (1 nm)
Gaussians: each colour is monochromatic, so its plane's MTF along an edge normal is the closed form of an
unobscured circular pupil's diffraction MTF at the colour's wavelength times the square pixel's sinc, which the
test computes itself. The scene has a neutral 5-degree edge (the methods' edge), a coloured one (white paint on
asphalt: its planes measured, no methods) and one too small to measure at the GSD (n/a rows with the reason)."""

from __future__ import annotations

import csv
import json
import math
import warnings

import jsonschema
import numpy as np
import pytest
import tifffile
from PIL import Image
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.results import results_schema
from satchain.scene.materials import material

PITCH_M, F_NUMBER = 5e-6, 10.0
CENTRE_M = {"red": 620e-9, "green": 540e-9, "blue": 460e-9}
TOL = 0.02  # issue 32 point 7: each raw colour plane's MTF within 0.02 of its prediction

SCENE = """
[scene]
width_m = 80.0
height_m = 60.0
background = 0.2
pixel_m = 0.07

[[items]]
kind = "slanted_edge"
id = "edge_neutral"
center_m = [22.0, 30.0]
size_m = 40.0
angle_deg = 5.0
measures = "act"

[[items]]
kind = "slanted_edge"
id = "edge_paint"
center_m = [62.0, 17.5]
size_m = 33.0
angle_deg = 8.0
measures = "act"
bright_material = "white_paint"
dark_material = "asphalt"

[[items]]
kind = "slanted_edge"
id = "edge_small"
center_m = [62.0, 48.0]
size_m = 14.0
angle_deg = 5.0
measures = "act"
"""

RESPONSES = "".join(f"[detector.cfa_responses.{c}]\ncenter_m = {v!r}\nfwhm_m = 1e-9\n" for c, v in CENTRE_M.items())


def _closed_form(colour: str, f_cy_per_px: float, normal_deg: float) -> float:
    """Diffraction MTF of a circular pupil at the colour's wavelength x the pixel's sinc, along the normal."""
    a = math.radians(normal_deg)
    x = f_cy_per_px / PITCH_M * CENTRE_M[colour] * F_NUMBER
    diff = 2 / math.pi * (math.acos(x) - x * math.sqrt(1 - x * x)) if x < 1 else 0.0
    return diff * abs(float(np.sinc(f_cy_per_px * math.cos(a)) * np.sinc(f_cy_per_px * math.sin(a))))


@pytest.fixture(scope="module")
def run(tmp_path_factory, minimal_system_toml):
    d = tmp_path_factory.mktemp("cfa_run")
    (d / "bayer.toml").write_text(minimal_system_toml.replace("[detector]\n", '[detector]\ncfa = "RGGB"\n') + RESPONSES)
    (d / "scene.toml").write_text(SCENE)
    (d / "run.toml").write_text('[system]\nfile = "bayer.toml"\n[scene]\nlayout = "scene.toml"\npixel_m = 0.07\n'
                                '[simulation]\nnoise = false\nunits = "reflectance"\n')  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = CliRunner().invoke(app, ["run", "--config", str(d / "run.toml"), "-o", str(d / "out")])
    out = d / "out"
    return res, out, json.loads((out / "results.json").read_text())


def _rows(results, kind="cfa_plane_mtf"):
    return {r["id"]: r for r in results["summary"] if r["kind"] == kind}


def test_each_raw_colour_plane_against_its_closed_form(run):
    res, _, results = run
    assert res.exit_code == 0, res.output
    assert "cfa edge_neutral red plane" in res.output  # the terminal table lists the planes' checks
    rows = _rows(results)
    edges = {e["id"]: e for e in results["cfa"]["edges"]}
    for edge in ("edge_neutral", "edge_paint"):
        e = edges[edge]
        assert e["reason"] is None and abs(abs(e["normal_deg"]) - {"edge_neutral": 5, "edge_paint": 8}[edge]) < 0.2
        for colour, ident in (("red", "red"), ("green", "green"), ("blue", "blue"), ("green", "green_quincunx")):
            r = rows[f"{edge}:{ident}"]
            key = "zone" if ident == "green_quincunx" else "grid"
            f = e["planes"][colour][f"f_{key}_cy_per_px"]
            truth = _closed_form(colour, f, e["normal_deg"])
            assert r["predicted"] == pytest.approx(truth, abs=2e-3), (edge, ident)  # the run's prediction
            assert r["measured"] == pytest.approx(truth, abs=TOL), (edge, ident)  # the measurement: physics
            assert r["pass"] is True and r["sigma"] is not None and r["sigma"] >= 0
        # where the planes sample (cy/px): red and blue on a 2 px grid, green's turned grid, its quincunx's zone
        t = math.radians(abs(e["normal_deg"]))
        assert e["planes"]["red"]["f_grid_cy_per_px"] == 0.25
        assert e["planes"]["green"]["f_grid_cy_per_px"] == pytest.approx(1 / (2 * math.sqrt(2)))
        assert e["planes"]["green"]["f_zone_cy_per_px"] == pytest.approx(0.5 / (math.cos(t) + math.sin(t)))
        assert e["planes"]["red"]["alias_cy_per_px"] == pytest.approx(0.5 * math.cos(t), abs=1e-9)
    assert not edges["edge_paint"]["neutral"] and "methods" not in edges["edge_paint"]


def test_an_edge_too_small_is_na_with_the_reason(run):
    _, _, results = run
    rows = _rows(results)
    for c in ("red", "green", "blue"):
        r = rows[f"edge_small:{c}"]
        assert r["pass"] is None and r["measured"] is None and "too small" in r["reason"]
    assert results["pass"] is True  # n/a rows aside, every check passes


def test_the_demosaicing_methods_side_by_side(run):
    _, _, results = run
    cfa = results["cfa"]
    assert cfa["methods_edge"] == "edge_neutral"
    m = {r["method"]: r for r in cfa["methods"]}
    assert list(m) == ["true", "bilinear", "malvar2004", "menon2007"]
    # the colour planes themselves read the luminance MTF50 of the colours' OTFs (a perfect interpolation)
    assert m["true"]["luminance_mtf50_cy_per_px"] == pytest.approx(m["true"]["luminance_mtf50_predicted"], abs=0.01)
    # bilinear interpolation is a low-pass and shows the most false colour at the edge
    assert m["bilinear"]["luminance_mtf50_cy_per_px"] < m["true"]["luminance_mtf50_predicted"] - 0.03
    for method in ("malvar2004", "menon2007"):
        assert m["bilinear"]["luminance_mtf50_cy_per_px"] < m[method]["luminance_mtf50_cy_per_px"]
        assert m["bilinear"]["false_colour_peak"] > m[method]["false_colour_peak"]
    for r in m.values():  # away from the edge a neutral scene stays grey (up to the colours' own PSF tails)
        assert r["flat_false_colour_peak"] < 0.005
    # no check rows: they are reported, not checked
    assert not [r for r in results["summary"] if r["kind"].startswith("cfa_") and r["kind"] != "cfa_plane_mtf"]


def test_results_json_summary_csv_and_the_budget_block(run):
    _, out, results = run
    jsonschema.Draft202012Validator(results_schema()).validate(results)
    with (out / "summary.csv").open() as fh:
        rows = [r for r in csv.DictReader(line for line in fh if not line.startswith("#"))]
    assert {r["id"] for r in rows if r["kind"] == "cfa_plane_mtf"} >= {"edge_neutral:red", "edge_small:blue"}
    assert all(r["unit"] and r["error_unit"] for r in rows)  # every check's units stated
    planes = results["cfa"]["planes_predicted"]
    assert planes["red"]["nyquist_cy_per_px"]["act"] == 0.25 and planes["green"]["alias_cy_per_px"]["act"] == 1.0
    assert results["cfa"]["pattern"] == "RGGB" and results["cfa"]["units"] == "reflectance"
    assert results["cfa"]["responses"]["green"].startswith("system file: Gaussian, centre 540.0 nm")


def test_the_raw_mosaic_and_the_demosaiced_images(run):
    _, out, results = run
    with tifffile.TiffFile(out / "images" / "cfa" / "raw.tif") as t:
        raw = t.asarray()
        meta = json.loads(t.pages[0].description)["satchain"]
    main = tifffile.imread(out / "images" / "simulated.tif")
    assert raw.shape == main.shape and meta["cfa_pattern"] == "RGGB" and meta["units"] == "reflectance"
    # the background (reflectance 0.2, grey) reads 0.2 at every photosite away from the targets, but for the far
    # tail of the Airy pattern (its energy beyond R falls as 1/R) of the bright squares 8 px and more away
    assert np.abs(raw[2:12, 10:80] - 0.2).max() < 5e-3
    # the bright sides: each photosite reads the reflectance at its colour's wavelength (white paint's spectrum,
    # and the neutral edge's 0.8 for every colour), within the far Airy tails of the dark sides (< 0.4 % here)
    paint, neutral = raw[30:38, 140:148], raw[56:64, 64:72]  # x 70-74 m, y 15-19 m; x 32-36 m, y 28-32 m
    white = material("white_paint")
    sites = {"red": (0, 0), "green": (0, 1), "blue": (1, 1)}  # RGGB
    for colour, (r, c) in sites.items():
        sl = (slice(r, None, 2), slice(c, None, 2))
        rho = float(np.interp(CENTRE_M[colour], white.wavelengths_m, white.reflectance))
        assert float(paint[sl].mean()) == pytest.approx(rho, abs=0.004), colour
        assert float(neutral[sl].mean()) == pytest.approx(0.8, abs=0.006), colour
    for method in ("bilinear", "malvar2004", "menon2007"):
        img = Image.open(out / "images" / "cfa" / f"rgb_{method}.png")
        assert img.mode == "RGB" and img.size == (raw.shape[1], raw.shape[0])
    assert set(results["cfa"]["files"]) <= {str(p.relative_to(out)) for p in (out / "images" / "cfa").iterdir()}


def test_the_report_section(run):
    _, out, results = run
    html = (out / "report.html").read_text()
    assert 'id="focal-cfa"' in html and "Demosaicing methods side by side" in html
    assert "Colour planes: MTF at each plane" in html and "Menon 2007" in html
    for fig in ("cfa_plane_mtf.png", "cfa_demosaic_crops.png"):
        assert (out / "figures" / fig).stat().st_size > 1000
    crop = results["cfa"]["crop"]
    assert crop["edge"] == "edge_neutral" and set(crop["rgb"]) == {"true", "bilinear", "malvar2004", "menon2007"}
    assert np.asarray(crop["rgb"]["bilinear"]).shape == (24, 24, 3)


def test_a_monochrome_system_has_no_section(run):
    """The section is None for a monochrome array, so the run is exactly as before (and results.json has no
    "cfa" key); the budget has no block."""
    import satchain
    from satchain.focal import cfa
    from satchain.results import BudgetResult
    from satchain.tf.budget import SystemOTF

    s = satchain.ImagingSystem.from_dict({"orbit": {"altitude_m": 5e5}, "detector": {"pitch_m": PITCH_M},
                                          "optics": {"aperture_diameter_m": 0.5, "f_number": F_NUMBER,
                                                     "wavelengths_m": [6e-7]}})  # fmt: skip
    calls = []
    assert cfa.section(None, BudgetResult(s, SystemOTF(s), {}), None, lambda *a: calls.append(a)) is None
    assert calls == [] and "cfa" not in satchain.budget(s).to_dict()
