"""``satchain measure``: every subcommand on TIFF, PNG (8/16 bit) and NPY input, outputs, and clear errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.special import ndtr
from typer.testing import CliRunner

from satchain.cli.measure import measure_app
from satchain.io.images import write_npy, write_png, write_tiff
from satchain.scene import (
    BarTarget,
    Car,
    HyperbolicWedge,
    Scene,
    SiemensStar,
    SlantedEdge,
    render_scene_to_file,
)

runner = CliRunner()
GSD = 0.49
SIGMA = 0.5  # px, Gaussian blur of the synthetic edge and star


def _edge_image(n=64, angle_deg=5.0):
    """Point-sampled Gaussian-blurred edge: its MTF along the normal is exactly exp(-2 pi^2 s^2 f^2)."""
    y, x = np.mgrid[0:n, 0:n].astype(float)
    t = np.deg2rad(angle_deg)
    d = (x - 31.6) * np.cos(t) - (y - 31.5) * np.sin(t)
    return 0.1 + 0.7 * ndtr(d / SIGMA)


def _star_image(n=161, cycles=32, mean=100.0, amp=40.0):
    """Sinusoidal star whose local grating is attenuated by the Gaussian MTF (exact, point-sampled)."""
    y, x = np.mgrid[0:n, 0:n].astype(float) - (n - 1) / 2
    r, th = np.hypot(x, y), np.arctan2(y, x)
    f = cycles / (2 * np.pi * np.maximum(r, 1e-9))
    return mean + amp * np.exp(-2 * np.pi**2 * SIGMA**2 * f**2) * np.cos(cycles * th)


def _gauss(f):
    return float(np.exp(-2 * np.pi**2 * SIGMA**2 * f**2))


def _write(tmp_path, name: str, img: np.ndarray, fmt: str, scale: float = 1.0):
    """Write ``img`` as tif-float, tif-uint16, png8, png16 or npy (NPY carries no pixel size)."""
    path = tmp_path / f"{name}_{fmt}.{'npy' if fmt == 'npy' else fmt[:3]}"
    if fmt == "tif-float":
        write_tiff(path, img.astype(np.float32), pixel_m=GSD)
    elif fmt == "tif-uint16":
        write_tiff(path, np.round(img * scale * 250).astype(np.uint16), pixel_m=GSD)
    elif fmt == "png8":
        write_png(path, np.round(img * scale).astype(np.uint8), pixel_m=GSD)
    elif fmt == "png16":
        write_png(path, np.round(img * scale * 250).astype(np.uint16), pixel_m=GSD)
    else:
        write_npy(path, img)
    return path


FORMATS = ["tif-float", "tif-uint16", "png8", "png16", "npy"]


def _ok(args):
    r = runner.invoke(measure_app, args)
    assert r.exit_code == 0, r.output
    return r


def _json(args):
    return json.loads(_ok([*args, "--json"]).stdout)


def _pixel_args(fmt):
    return ["--pixel-m", str(GSD)] if fmt == "npy" else []


@pytest.mark.parametrize("fmt", FORMATS)
def test_edge_every_format(tmp_path, fmt):
    path = _write(tmp_path, "edge", _edge_image(), fmt, scale=255)
    d = _json(["edge", str(path), *_pixel_args(fmt)])
    keys = {"f_cy_per_px", "mtf", "mtf_at_nyquist", "mtf50_cy_per_px", "angle_deg", "rer", "overshoot"}
    assert keys <= set(d)
    assert d["pixel_m"] == pytest.approx(GSD)  # from the file's metadata, or --pixel-m for NPY
    assert d["angle_deg"] == pytest.approx(5.0, abs=0.05) and d["direction"] == "ACT"
    assert d["mtf_at_nyquist"] == pytest.approx(_gauss(0.5), abs=0.01)
    f = np.asarray(d["f_cy_per_px"])
    np.testing.assert_allclose(d["f_cy_per_m_ground"], f / GSD)
    band = f <= 0.5
    truth = np.exp(-2 * np.pi**2 * SIGMA**2 * f[band] ** 2)
    assert np.max(np.abs(np.asarray(d["mtf"])[band] - truth)) < 0.015


def test_edge_tables_roi_and_outputs(tmp_path):
    path = _write(tmp_path, "edge", _edge_image(96), "tif-float")
    r = _ok(["edge", str(path), "--roi", "10,8,90,88", "-o", str(tmp_path / "out")])
    assert "MTF at Nyquist" in r.stdout and "slanted edge" in r.stdout
    names = {p.name for p in (tmp_path / "out").iterdir()}
    assert names == {"edge.json", "edge.png"}  # no temporary files left behind
    d = json.loads((tmp_path / "out" / "edge.json").read_text())
    assert d["roi"] == [10, 8, 90, 88] and d["mtf_at_nyquist"] == pytest.approx(_gauss(0.5), abs=0.01)
    assert (tmp_path / "out" / "edge.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("fmt", ["tif-float", "png8", "png16", "npy"])
def test_star_formats(tmp_path, fmt):
    path = _write(tmp_path, "star", _star_image(), fmt)
    d = _json(["star", str(path), "--cycles", "32", "--input-modulation", "0.4", *_pixel_args(fmt)])
    for k in ("ACT", "ALT", "D45", "D135"):
        assert d["mtf_at_nyquist"][k] == pytest.approx(_gauss(0.5), abs=0.02), k
    np.testing.assert_allclose(d["f_cy_per_m_ground"], np.asarray(d["f_cy_per_px"]) / GSD)


def test_star_center_in_image_pixels_with_roi_and_plot(tmp_path):
    img = np.full((181, 201), 100.0)
    img[10:171, 30:191] = _star_image()  # star centre at x = 110, y = 90
    path = _write(tmp_path, "star", img, "npy")
    args = [
        "star",
        str(path),
        "--cycles",
        "32",
        "--roi",
        "25,5,196,176",
        "--center",
        "110,90",
        "--radius",
        "78",
    ]
    r = _ok([*args, "--input-modulation", "0.4", "-o", str(tmp_path / "o")])
    assert "MTF at Nyquist, ACT" in r.stdout
    d = json.loads((tmp_path / "o" / "star.json").read_text())
    assert d["center_xy_px"] == [85.0, 85.0]  # in the region's coordinates
    assert d["mtf_at_nyquist"]["ALT"] == pytest.approx(_gauss(0.5), abs=0.02)
    assert (tmp_path / "o" / "star.png").stat().st_size > 5000


def _bars_image():
    """Two bar groups: period 8 px, levels 50/150 (flat plateaus: the reference); period 4 px blurred to its
    fundamental, 100 +- 25 with the peaks between samples (the old sampled max - min gave 0.354): CTF 1 and 0.5."""
    x = np.arange(120)
    row = np.full(120, 100.0)
    g1 = x < 56
    row[g1] = np.where((x[g1] // 4) % 2 == 0, 150.0, 50.0)
    g2 = (x >= 60) & (x < 116)
    row[g2] = 100 + 25 * np.cos(2 * np.pi * (x[g2] - 60.5) / 4)
    return np.tile(row, (40, 1))


@pytest.mark.parametrize("fmt", ["tif-uint16", "png8", "png16", "npy"])
def test_bars_groups(tmp_path, fmt):
    path = _write(tmp_path, "bars", _bars_image(), fmt)
    args = [
        "bars",
        str(path),
        "--periods-px",
        "8,4",
        "--group-roi",
        "0,0,56,40",
        "--group-roi",
        "60,0,116,40",
    ]
    d = _json([*args, *_pixel_args(fmt)])
    np.testing.assert_allclose(d["ctf"], [1.0, 0.5], atol=0.01)
    np.testing.assert_allclose(d["f_cy_per_px"], [0.125, 0.25])
    assert d["direction"] == "ACT" and len(d["mtf"]) == 2


def test_bars_single_roi_alt_and_outputs(tmp_path):
    path = _write(tmp_path, "bars", _bars_image().T.copy(), "tif-float")
    args = ["bars", str(path), "--periods-px", "4", "--roi", "0,60,40,116", "--direction", "ALT"]
    r = _ok([*args, "--levels", "50,150", "-o", str(tmp_path / "o")])
    assert "CTF" in r.stdout
    d = json.loads((tmp_path / "o" / "bars.json").read_text())
    assert d["ctf"] == [pytest.approx(0.5)] and d["direction"] == "ALT"
    assert (tmp_path / "o" / "bars.png").exists()


def _pixel_gauss_step(d, s):
    """Unit step blurred by a Gaussian (sigma ``s`` px) and integrated over a 1 px pixel centred at ``d``."""
    from scipy.stats import norm

    def g(z):
        return z * norm.cdf(z) + norm.pdf(z)

    return s * (g((d + 0.5) / s) - g((d - 0.5) / s))


def _bar_target(periods, s=0.4, dark=40.0, bright=160.0, rows=12):
    """3-bar groups side by side, exact at pixel centres; each ROI from the first to the last bar centre."""
    x = np.arange(sum(int(np.ceil(6.5 * p)) for p in periods) + 10, dtype=float)
    row, rois, start = np.full(x.size, dark), [], 5.3
    for p in periods:
        for k in range(3):
            u0 = start + k * p
            row += (bright - dark) * (_pixel_gauss_step(x - u0, s) - _pixel_gauss_step(x - u0 - p / 2, s))
        c0, c1 = start + p / 4, start + 2 * p + p / 4
        rois.append(f"{int(np.ceil(c0))},0,{int(np.floor(c1)) + 1},{rows}")
        start += int(np.ceil(6.5 * p))
    return np.tile(row, (rows, 1)), rois


def _coltman_gauss(f, s=0.4):
    k = np.arange(1, 2001, 2)
    return float(
        4 / np.pi * np.sum((-1.0) ** ((k - 1) // 2) * np.exp(-2 * np.pi**2 * s * s * (k * f) ** 2) * np.sinc(k * f) / k)
    )


def test_bars_target_corrected_to_the_square_wave_ctf(tmp_path):
    """A 4-group target of a sharp system (Gaussian 0.4 px): the 4 px group's 3rd harmonic folds onto its
    fundamental (a lone group reads up to 0.044 off); in the target every group is within 0.03 of Coltman's
    square-wave CTF and the correction is reported; --bars-per-group 0 reports none; 1 is refused."""
    periods = (12.0, 6.0, 4.0, 3.0)
    img, rois = _bar_target(periods)
    path = _write(tmp_path, "target", img, "npy")
    args = ["bars", str(path), "--periods-px", ",".join(f"{p:g}" for p in periods), "--levels", "40,160"]
    for r in rois:
        args += ["--group-roi", r]
    d = _json(args)
    truth = [_coltman_gauss(1 / p) for p in periods]
    np.testing.assert_allclose(d["ctf"], truth, atol=0.03)
    assert len(d["ctf_correction"]) == 4 and all(abs(c) < 0.05 for c in d["ctf_correction"])
    grating = _json([*args, "--bars-per-group", "0"])
    assert grating["ctf_correction"] is None
    _err([*args, "--bars-per-group", "1"], "--bars-per-group")


def test_bars_table_names_a_refused_group_instead_of_nan(tmp_path):
    """One group of a 4-group target replaced by a 2.7 px grating (no bars of its 6 px period; a uniform grey would
    be a CTF ~0 at the noise floor, issue 29): the table says "refused" in its row and gives the reason; no "nan"
    is printed; the other groups keep their numbers."""
    periods = (12.0, 6.0, 4.0, 3.0)
    img, rois = _bar_target(periods)
    x0, _, x1, _ = (int(v) for v in rois[1].split(","))
    img[:, x0 - 3 : x1 + 3] = 100.0 + 50.0 * np.cos(2 * np.pi * np.arange(x0 - 3, x1 + 3) / 2.7)
    path = _write(tmp_path, "target", img, "npy")
    args = ["bars", str(path), "--periods-px", ",".join(f"{p:g}" for p in periods), "--levels", "40,160"]
    for r in rois:
        args += ["--group-roi", r]
    res = runner.invoke(measure_app, args, terminal_width=200)
    assert res.exit_code == 0, res.output
    assert "nan" not in res.output.lower()
    assert "refused" in res.output and "group 1 (period 6 px) refused:" in " ".join(res.output.split())
    d = _json(args)
    assert d["ctf"][1] is None or d["ctf"][1] != d["ctf"][1]
    assert all(isinstance(c, float) and 0 < c < 1 for i, c in enumerate(d["ctf"]) if i != 1)


def _wedge_image():
    """Stripes 6 -> 1.05 px wide (linear) whose contrast is set to 0.8 (50 - x) / 40: 15 % at x = 42.5."""
    y, x = np.mgrid[0:40, 0:100]
    lw = 6.0 - 0.05 * x
    return 100 + 80 * np.sign(np.sin(np.pi * y / lw)) * np.clip((x - 50) / -40, 0, 1)


@pytest.mark.parametrize("fmt", ["tif-float", "png8", "npy"])
def test_wedge_explicit_linear_profile(tmp_path, fmt):
    path = _write(tmp_path, "wedge", _wedge_image(), fmt)
    args = [
        "wedge",
        str(path),
        "--line-width-start-px",
        "6",
        "--line-width-end-px",
        "1.05",
        "--profile",
        "linear",
    ]
    d = _json([*args, *_pixel_args(fmt)])
    assert d["resolved_position_px"] == pytest.approx(42.5, abs=0.1)
    assert d["resolved_line_width_px"] == pytest.approx(3.875, abs=0.01)
    assert d["resolved_line_width_m"] == pytest.approx(3.875 * GSD, abs=0.01)
    assert d["line_width_px"][0] == 6.0 and d["line_width_px"][-1] == pytest.approx(1.05)


def test_wedge_hyperbolic_profile_and_plot(tmp_path):
    path = _write(tmp_path, "wedge", _wedge_image(), "tif-float")
    args = ["wedge", str(path), "--line-width-start-px", "6", "--line-width-end-px", "1.05"]
    r = _ok([*args, "-o", str(tmp_path / "o")])
    assert "resolved line width" in r.stdout
    d = json.loads((tmp_path / "o" / "wedge.json").read_text())
    lw = np.asarray(d["line_width_px"])
    np.testing.assert_allclose(1 / lw, np.linspace(1 / 6, 1 / 1.05, 100))  # 1/width linear: a hyperbola
    assert d["resolved_position_px"] == pytest.approx(42.5, abs=0.1)  # position is set by the contrast ramp
    assert (tmp_path / "o" / "wedge.png").exists()


@pytest.fixture(scope="module")
def scene_files(tmp_path_factory):
    """A small scene rendered to TIFF (0.25 m pixels, with metadata) and its truth file."""
    items = (
        SlantedEdge("edge", center_m=(10.0, 10.0), size_m=16.0, angle_deg=6.0),
        SiemensStar("star", center_m=(10.0, 29.0), radius_m=7.0, cycles=24),
        HyperbolicWedge("wedge", origin_m=(22.0, 2.0), length_m=15.0, line_width_end_m=0.25),
        BarTarget("bars", origin_m=(21.0, 22.0), periods_m=(2.0, 1.0, 0.5, 0.4), gap_m=1.0),
        Car("car", origin_m=(34.0, 30.0)),
    )
    d = tmp_path_factory.mktemp("scene")
    files = render_scene_to_file(Scene(40.0, 38.0, items, pixel_m=0.25), d / "scene.tif")
    return files["tiff"], files["truth"]


def test_auto_json_and_outputs(scene_files, tmp_path):
    tif, truth = scene_files
    d = _json(["auto", str(tif), "--truth", str(truth)])
    assert d["pixel_m"] == 0.25
    measured = {e["id"] for k in ("slanted_edges", "siemens_star", "bar_targets", "hyperbolic_wedge") for e in d[k]}
    skipped = {s["id"]: s["reason"] for s in d["skipped"]}
    assert measured == {"edge", "star", "bars", "wedge"}
    assert "no measurement defined" in skipped["car"] and "Nyquist" in skipped["bars/group_3"]
    assert d["slanted_edges"][0]["angle_deg"] == pytest.approx(6.0, abs=0.2)
    r = _ok(["auto", str(tif), "--truth", str(truth), "-o", str(tmp_path / "o")])
    assert "slanted edges" in r.stdout and "not measured" in r.stdout
    names = {p.name for p in (tmp_path / "o").iterdir()}
    expected = {
        "slanted_edge_edge.png",
        "siemens_star_star.png",
        "bar_target_bars.png",
        "hyperbolic_wedge_wedge.png",
    }
    assert names == {"auto.json", *expected}


def test_wedge_from_truth(scene_files):
    tif, truth = scene_files
    d = _json(["wedge", str(tif), "--truth", str(truth)])
    assert d["id"] == "wedge" and d["direction"] == "ALT" and d["threshold"] == 0.15
    assert d["line_width_m"][0] <= 1.25 and "resolution_m" in d
    r = runner.invoke(measure_app, ["wedge", str(tif), "--truth", str(truth), "--id", "edge"])
    assert r.exit_code == 2 and "not a hyperbolic wedge" in r.stderr


def _err(args, *needles):
    r = runner.invoke(measure_app, args)
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output
    for n in needles:
        assert n in r.stderr, r.stderr
    return r


def test_errors_exit_2_with_a_clear_message(tmp_path):
    results = []
    edge = _write(tmp_path, "edge", _edge_image(), "tif-float")
    results.append(_err(["edge", str(tmp_path / "missing.tif")], "error:", "no such file"))
    results.append(_err(["edge", str(edge), "--roi", "1,2,3"], "--roi", "4 comma-separated numbers"))
    results.append(_err(["edge", str(edge), "--roi", "1,2,3.5,9"], "--roi", "integers"))
    results.append(
        _err(["edge", str(edge), "--roi", "50,0,64,64"], "error:", "flat")
    )  # beyond the edge: no edge in the ROI
    results.append(_err(["edge", str(edge), "--roi", "0,0,5,5"], "too small"))
    results.append(_err(["edge", str(edge), "--roi", "0,0,100,20"], "roi"))
    results.append(_err(["edge", str(edge), "--pixel-m", "-1"], "--pixel-m"))
    noise = 0.5 + 0.01 * np.random.default_rng(1).normal(size=(64, 64))
    results.append(_err(["edge", str(_write(tmp_path, "noise", noise, "npy"))], "no edge found"))
    flat = _write(tmp_path, "flat", np.full((64, 64), 0.3), "npy")
    results.append(_err(["edge", str(flat)], "flat"))
    nan = _edge_image()
    nan[10, 10] = np.nan
    results.append(_err(["edge", str(_write(tmp_path, "nan", nan, "npy"))], "NaN"))
    jpg = tmp_path / "x.jpg"
    jpg.write_bytes(b"not an image")
    results.append(_err(["edge", str(jpg)], "unsupported suffix"))
    bars = _write(tmp_path, "bars", _bars_image(), "npy")
    results.append(_err(["bars", str(bars), "--periods-px", "8,4"], "--group-roi"))
    results.append(_err(["bars", str(bars), "--periods-px", "8,x"], "--periods-px"))
    results.append(_err(["wedge", str(bars)], "--line-width-start-px"))
    results.append(_err(["star", str(bars)], "--cycles"))  # typer's own usage error, also status 2
    results.append(_err(["star", str(flat), "--cycles", "32"], "flat"))
    bad = tmp_path / "truth.json"
    bad.write_text("{not json")
    results.append(_err(["auto", str(edge), "--truth", str(bad)], "not JSON"))
    results.append(_err(["auto", str(edge), "--truth", str(tmp_path / "none.json")], "no such file"))

    assert len(results) >= 15 and all(r.exit_code == 2 and r.stderr for r in results)


# issue 29 follow-up: item 5's rule for measure: a --pixel-m that contradicts the GeoTIFF's georeference is refused
def _geotiff_049(tmp_path):
    import rasterio
    from rasterio import Affine

    n = 160
    y, x = np.mgrid[0:n, 0:n]
    a = np.where((x - n / 2) + 0.1 * (y - n / 2) > 0, 0.8, 0.1).astype("float32")
    path = tmp_path / "g.tif"
    with rasterio.open(path, "w", driver="GTiff", width=n, height=n, count=1, dtype="float32", crs="EPSG:32636",
                       transform=Affine(0.49, 0, 5e5, 0, -0.49, 4.4e6)) as d:  # fmt: skip
        d.write(a, 1)
    return path


@pytest.mark.parametrize(
    "args",
    [
        ["edge"],
        ["find"],
        ["star", "--cycles", "32"],
        ["bars", "--periods-px", "4"],
        ["wedge"],
        ["jitter", "--line-time", "1e-4"],
    ],  # fmt: skip
)
def test_a_pixel_m_that_contradicts_the_geotiff_is_refused_by_every_measure_command(tmp_path, args):
    path = _geotiff_049(tmp_path)
    r = runner.invoke(measure_app, [args[0], str(path), *args[1:], "--pixel-m", "5"])
    line = " ".join(r.output.split())
    assert r.exit_code == 2 and "--pixel-m = 5" in line and "0.49 m" in line and "contradicts" in line, r.output


def test_a_pixel_m_that_agrees_with_the_geotiff_uses_the_files(tmp_path):
    path = _geotiff_049(tmp_path)
    r = runner.invoke(measure_app, ["edge", str(path), "--pixel-m", "0.4901", "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output[r.output.index("{") :])["pixel_m"] == pytest.approx(0.49, rel=1e-12)


@pytest.mark.parametrize("value", ["0", "-1", "1e-30", "nan", "1e300"])
def test_a_line_time_outside_its_range_is_one_message_with_the_real_range(tmp_path, value):
    path = _geotiff_049(tmp_path)
    r = runner.invoke(measure_app, ["jitter", str(path), "--line-time", value])
    line = " ".join(r.output.split())
    assert r.exit_code == 2 and "--line-time" in line and "must be in [1e-09, 1000] s" in line, r.output
    assert "inf" not in line.replace(value, "")
