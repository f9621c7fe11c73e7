"""The HTML report of ``satchain run``: structure, self-containment, figures that decode and are legible,
the curves as CSV, and the predicted edge curves against closed forms."""

from __future__ import annotations

import base64
import csv
import io
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.text import Text
from PIL import Image

from satchain.comparison import BAR_COMPARE_MAX_CY_PER_PX
from satchain.config.run import load_run_config
from satchain.pipeline import run_pipeline
from satchain.report import _save, compare_plots, curves, figures, gallery, radiometry_plot, run_figures
from satchain.report.compare_plots import PRINT_WIDTH_IN
from satchain.report.html import SECTIONS

#: The reduced end-to-end scene (tests/conftest.py) plus a bar target.
BARS_TOML = """
[[items]]
kind = "bar_target"
id = "bars"
origin_m = [75.0, 112.0]
periods_m = [4.0, 3.0, 2.0, 1.5]
orientation = "act"
"""

FIGURE_MODULES = (compare_plots, run_figures, gallery, figures, radiometry_plot)


@pytest.fixture(scope="module")
def run(tmp_path_factory, reduced_scene_toml):
    """One reduced run; every figure the report draws is captured (and saved as usual)."""
    d = tmp_path_factory.mktemp("report")
    (d / "scene.toml").write_text(reduced_scene_toml + BARS_TOML)
    (d / "run.toml").write_text('[scene]\nlayout = "scene.toml"\npixel_m = 0.07\n[simulation]\nseed = 5\n')
    captured = []

    def capture(fig, path, **kw):
        FigureCanvasAgg(fig).draw()
        captured.append((str(path), _text_problems(fig)))
        _save.save_figure(fig, path, **kw)

    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SATCHAIN_FIGURE_PROCESSES", "0")  # every figure drawn here, where it is captured
        for mod in FIGURE_MODULES:
            mp.setattr(mod, "save_figure", capture)
        res = run_pipeline(load_run_config(d / "run.toml"), d / "out")
    out = d / "out"
    return SimpleNamespace(out=out, res=res, html=(out / "report.html").read_text(), figures=captured)


def _text_problems(fig) -> list[str]:
    """Texts smaller than 9 pt when the figure is shown at its size or scaled to an A4 text block, sticking
    out of the figure (clipped), or a title, axis label or tick label overlapping another (the fixed layouts'
    margins too small)."""
    width_in = fig.get_figwidth()
    scale = min(1.0, PRINT_WIDTH_IN / width_in)
    bad = []
    for t in fig.findobj(Text):
        if not t.get_visible() or not t.get_text().strip():
            continue
        size = t.get_fontsize() * scale
        if size < 9.0 - 1e-6:
            bad.append(f"{t.get_text()!r}: {size:.1f} pt")
    tight = fig.get_tightbbox(fig.canvas.get_renderer())  # inches, drawn artists only
    w, h = fig.get_size_inches()
    if tight.x0 < -0.01 or tight.y0 < -0.01 or tight.x1 > w + 0.01 or tight.y1 > h + 0.01:
        bad.append(f"drawn beyond the figure: {tight} vs {w:.2f} x {h:.2f} in")
    return bad + _overlaps(fig)


def _overlaps(fig) -> list[str]:
    """Pairs of the figure's frame texts (suptitle, axes titles, axis labels, tick labels) whose boxes overlap."""
    r = fig.canvas.get_renderer()
    texts = [fig._suptitle] if fig._suptitle is not None else []
    for ax in fig.axes:
        texts += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label]
        for axis in (ax.xaxis, ax.yaxis):  # the ticks drawn (inside the view)
            texts += [lab for tick in axis._update_ticks() for lab in (tick.label1, tick.label2)]
    boxes = [(t.get_text(), t.get_window_extent(r)) for t in texts if t.get_visible() and t.get_text().strip()]
    return [
        f"{a!r} overlaps {b!r}"
        for i, (a, ba) in enumerate(boxes)
        for b, bb in boxes[i + 1 :]
        if min(ba.x1, bb.x1) - max(ba.x0, bb.x0) > 0.5 and min(ba.y1, bb.y1) - max(ba.y0, bb.y0) > 0.5
    ]


def _images(html: str) -> list[bytes]:
    return [base64.b64decode(b) for b in re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)]


def test_sections_in_order_with_table_of_contents(run):
    html = run.html
    assert '<meta name="viewport" content="width=device-width, initial-scale=1">' in html
    shown = [sid for sid, _ in SECTIONS if sid != "focal-plane"]  # only a system with bands, a CFA or two arrays
    assert '<h2 id="focal-plane">' not in html and 'href="#focal-plane"' not in html
    positions = [html.index(f'<h2 id="{sid}">') for sid in shown]
    assert positions == sorted(positions)
    for sid in shown:
        assert f'href="#{sid}"' in html  # the table of contents links every section
    # results first: the verdict and key figures precede every section
    assert html.index('class="verdict') < positions[0]
    assert html.index("MTF at Nyquist, along-track") < positions[0]


def test_self_contained(run):
    html = run.html
    assert "<script" not in html and "<link" not in html and "@import" not in html
    assert not re.search(r'(src|href)="(https?:)?//', html)
    assert not re.search(r"url\((?!data:)", html)
    for src in re.findall(r'<img[^>]*\ssrc="([^"]+)"', html):
        assert src.startswith("data:image/png;base64,")


def test_every_figure_decodes_and_every_target_is_shown(run):
    images = _images(run.html)
    assert len(images) == run.html.count("<img")
    for png in images:
        Image.open(io.BytesIO(png)).verify()
    res = run.res
    for key, prefix in (("slanted_edges", "edge_"), ("siemens_star", "star_"), ("bar_targets", "bars_")):
        for item in res[key]:
            assert (run.out / "figures" / f"{prefix}{item['id']}.png").is_file()
    assert (run.out / "figures" / "wedge_wedge_h.png").is_file()
    assert (run.out / "figures" / "image_rois.png").is_file()
    # every measurement target has a thumbnail at truth, focal plane and detector, each a zoomable image
    n_targets = 5
    assert run.html.count('<details class="zoom">') == 3 * n_targets
    for name in ("edge_act", "edge_alt", "star", "wedge_h", "bars"):
        assert f"{name}, ground truth" in run.html and f"{name}, detector" in run.html


def test_thumbnails_cover_the_target_at_each_sampling(run):
    """The detector thumbnail of the 60 m edge square spans 60 m / 0.49 m pixels; the ground truth spans it
    at 7 cm -- both independent of the report code (geometry of the scene and the camera)."""
    html = run.html
    m = re.search(r'alt="edge_act, ground truth" width="(\d+)" height="(\d+)"', html)
    d = re.search(r'alt="edge_act, detector" width="(\d+)" height="(\d+)"', html)
    assert m and d
    side_m = 60.0  # the default slanted-edge square
    assert int(m.group(1)) == pytest.approx(side_m / 0.07, abs=2)
    assert int(d.group(1)) == pytest.approx(side_m / 0.49, abs=2)


def test_figures_are_legible_and_not_clipped(run):
    assert len(run.figures) >= 8
    problems = {p: bad for p, bad in run.figures if bad}
    assert not problems, problems


def test_tables_have_words_and_units_not_ids_or_exponents(run):
    text = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", run.html)
    assert not re.search(r"\d\.\d+e[-+]\d", text), "numbers in exponent notation"
    for label in ("quantum efficiency", "read noise", "full well", "ADC bit depth", "TDI stages"):
        assert label in text
    assert "scene SNR" in text and "contrast SNR" in text
    assert "12.28 %" in text and "52.5 cm" in text  # the paper's own results, cited
    assert "Table 1 fit" in text
    # summary: one row per check with a difference column
    n_checks = len(run.res["summary"])
    assert text.count('data-label="difference"') == n_checks
    # the not-measured list is grouped: one row per (kind, reason), counts adding up
    skipped = run.res["skipped"]
    groups = {(s["kind"], s["reason"]) for s in skipped}
    counts = [int(c) for c in re.findall(r'<td class="l">[^<]*</td><td>(\d+)</td><td class="l">', text)]
    assert len(counts) == len(groups) and sum(counts) == len(skipped)


def _read_csv(path):
    lines = path.read_text().splitlines()
    assert lines[0].startswith("# ")
    rows = list(csv.DictReader(lines[1:]))
    return rows


def test_every_curve_as_csv(run):
    d = run.out / "curves"
    for name in curves.CSV_FAMILIES:
        assert (d / name).is_file(), name
        assert name in run.html  # linked from the report
    mtf = _read_csv(d / "edges_mtf.csv")
    assert {"edge_id", "f_cy_per_px", "mtf_measured", "mtf_predicted"} <= set(mtf[0])
    for e in run.res["slanted_edges"]:
        rows = [r for r in mtf if r["edge_id"] == e["id"]]
        f = np.array([float(r["f_cy_per_px"]) for r in rows])
        pred = np.array([float(r["mtf_predicted"]) for r in rows])
        assert np.interp(0.5, f, pred) == pytest.approx(e["mtf_at_nyquist_predicted"], abs=2e-3)
        assert float(rows[0]["mtf_measured"]) == pytest.approx(1.0, abs=0.02)  # MTF(0) = 1
        # the measurement's 1-sigma noise beside every value; at Nyquist it is results.json's
        sig = np.array([float(r["mtf_sigma_measured"]) for r in rows])
        assert np.all(sig[1:] > 0) and np.interp(0.5, f, sig) == pytest.approx(e["mtf_at_nyquist_sigma"], rel=0.05)
        assert isinstance(e["flags"], list)
    esf = _read_csv(d / "edges_esf_lsf.csv")
    for eid in {r["edge_id"] for r in esf}:
        rows = [r for r in esf if r["edge_id"] == eid]
        x = np.array([float(r["x_px"]) for r in rows])
        lsf_p = np.array([float(r["lsf_predicted_per_px"]) for r in rows])
        lsf_m = np.array([float(r["lsf_measured_per_px"]) for r in rows])
        assert np.trapezoid(lsf_p, x) == pytest.approx(1.0, abs=0.02)  # OTF(0) = 1
        assert np.max(np.abs(lsf_m - lsf_p)) < 0.1 * lsf_p.max()  # the prediction matches the measurement
    bars = _read_csv(d / "bars_ctf.csv")
    assert {r["compared"] for r in bars} <= {"yes", "no"}
    for r in bars:  # groups with fewer than 5 px per period are not compared
        assert (r["compared"] == "yes") == (float(r["f_cy_per_px"]) <= BAR_COMPARE_MAX_CY_PER_PX)
    star = _read_csv(d / "star_mtf.csv")
    assert {r["direction"] for r in star} == {"ACT", "ALT", "D45", "D135"}
    wedge = _read_csv(d / "wedge_contrast.csv")
    assert {"line_width_m", "contrast_measured", "ctf_coltman_predicted"} <= set(wedge[0])
    system = _read_csv(d / "system_mtf_ctf.csv")
    assert float(system[0]["mtf_system_alt"]) == pytest.approx(1.0)


class _GaussianOTF:
    """An OTF exp(-2 pi^2 s^2 f^2) (f in cy/px of a 5 um pitch): its LSF is a Gaussian of sigma s px."""

    def __init__(self, sigma_px: float):
        self.sigma = sigma_px
        det = SimpleNamespace(pitch_x_m=5e-6, pitch_y_m=5e-6)
        self.system = SimpleNamespace(detector=det)
        self.cutoff_cy_per_mm = 4.0 / 5e-3  # 4 cy/px: the Gaussian is negligible beyond

    def __call__(self, fx_mm, fy_mm):
        f_px = np.hypot(fx_mm, fy_mm) * 5e-3
        return np.exp(-2 * np.pi**2 * self.sigma**2 * f_px**2)


@pytest.mark.parametrize("sigma", [0.4, 0.8, 1.5])
def test_predicted_lsf_and_esf_closed_form(sigma):
    x = np.linspace(-8, 8, 321)
    lsf, esf = curves.predicted_lsf(_GaussianOTF(sigma), (0.6, 0.8), x)
    gauss = np.exp(-0.5 * (x / sigma) ** 2) / (sigma * math.sqrt(2 * math.pi))
    assert np.max(np.abs(lsf - gauss)) < 1e-3 * gauss.max()
    erf = np.array([0.5 * (1 + math.erf(v / (sigma * math.sqrt(2)))) for v in x])
    assert np.max(np.abs(esf - erf)) < 2e-3


def test_crossing_of_a_line():
    f = np.linspace(0, 1, 11)
    m = 1 - f  # falls to 0.5 at 0.5 and to 0.1 at 0.9
    assert curves.crossing(f, m, 0.5) == pytest.approx(0.5)
    assert curves.crossing(f, m, 0.1) == pytest.approx(0.9)
    assert curves.crossing(f, m + 1, 0.5) is None


def test_no_pyplot_state():
    for mod in FIGURE_MODULES:
        assert not hasattr(mod, "plt"), mod.__name__


def test_tables_tolerate_na_and_the_overall_flag():
    """results.json may carry "n/a" for unmeasurable checks and an overall ``passed`` flag: shown, not crashed on."""
    from satchain.report import tables

    res = {
        "passed": False,
        "tolerances": {"edge_mtf_at_nyquist": 0.02, "wedge_resolution_rel": 0.15, "niirs": 0.2},
        "slanted_edges": [
            {
                "id": "e1",
                "direction": "ACT",
                "mtf_at_nyquist_measured": 0.21,
                "mtf_at_nyquist_predicted": 0.2,
                "pass": True,
            },
            {
                "id": "e2",
                "direction": "ALT",
                "mtf_at_nyquist_measured": "n/a",
                "mtf_at_nyquist_predicted": 0.12,
                "pass": "n/a",
            },
        ],
        "hyperbolic_wedge": [
            {"id": "w", "axis": "ALT", "resolution_m": None, "resolution_predicted_m": 0.49, "pass": "n/a"}
        ],
        "niirs": {"giqe5_measured": float("nan"), "giqe5_predicted": 5.2, "pass": "n/a"},
        "summary": [{"pass": True}, {"pass": "n/a"}, {"pass": None}],
    }
    rows = tables.summary_rows(res)
    assert [r["status"] for r in rows] == ["pass", "n/a", "n/a", "n/a"]
    assert rows[0]["difference"] == "+0.010" and rows[1]["difference"] == "–"
    assert rows[2]["predicted"] == "49.0 cm" and rows[2]["measured"] == "–"
    v = tables.verdict(res)
    assert v["passed"] is False and (v["n_pass"], v["n_fail"], v["n_na"]) == (1, 0, 2)
    del res["passed"]
    assert tables.verdict(res)["passed"] is True  # no check failed and one passed
    assert tables.key_figures(res, {})[2]["measured"] == "–"  # the only ALT edge is n/a


# ---------------------------------------------------------------------------------------------- issue 18: 5 and 6


def _all_flags(res) -> list[str]:
    return [
        str(f)
        for key in ("slanted_edges", "siemens_star", "bar_targets", "hyperbolic_wedge")
        for x in res.get(key, [])
        for f in x.get("flags") or []
    ] + [str(w) for w in res.get("warnings") or []]


def test_every_flag_of_results_json_is_in_the_report_beside_its_measurement(run):
    from markupsafe import escape

    flags = _all_flags(run.res)
    assert flags, "the reduced run with its bar target carries flags"
    for key, section in (("slanted_edges", "edges"), ("siemens_star", "star"), ("bar_targets", "bars")):
        lo = run.html.index(f'<h2 id="{section}">')
        hi = run.html.index("<h2 ", lo + 1)
        for x in run.res.get(key, []):
            for f in x.get("flags") or []:
                assert str(escape(f)) in run.html[lo:hi], (x["id"], f)  # in the target's own section
    for f in flags:
        assert str(escape(f)) in run.html


def test_summary_rows_show_sigma_z_and_every_row_has_sigma_or_a_reason(run):
    rows = run.res["summary"]
    for r in rows:
        assert (r["sigma"] is not None) != bool(r["sigma_null_means"]), r
        if r["sigma"] is not None and r["error"] is not None:
            assert r["z"] == pytest.approx(r["error"] / r["sigma"])
            assert r["tolerance_inside_noise"] is (r["tolerance_value"] < r["sigma"] and abs(r["z"]) < 3)
    assert sum(r["sigma"] is not None for r in rows if r["kind"] != "wedge_resolution") >= len(rows) - 2
    text = run.html
    assert text.count('data-label="σ"') == len(rows) and text.count('data-label="z"') == len(rows)


def test_summary_csv_matches_results_json(run):
    lines = (run.out / "summary.csv").read_text().splitlines()
    assert lines[0].startswith("# ") and "unit" in lines[0]
    rows = list(csv.DictReader(lines[1:]))
    assert len(rows) == len(run.res["summary"])
    for c, r in zip(rows, run.res["summary"], strict=True):
        assert (c["figure"], c["kind"], c["id"] or None) == (r["figure"], r["kind"], r["id"])
        assert c["unit"] and c["error_unit"]
        for k in ("measured", "predicted", "error", "sigma", "z", "tolerance_value"):
            if r[k] is None:
                assert c[k] == ""
            else:
                assert float(c[k]) == pytest.approx(r[k], rel=1e-9, abs=1e-12)
        assert c["pass"] == {True: "true", False: "false", None: ""}[r["pass"]]
    assert not list(run.out.glob(".summary.csv*")), "written atomically: no temporary left"


def test_results_before_the_gallery_and_overlays_on_every_thumbnail(run):
    html = run.html
    gallery = html.index('<details class="zoom">')
    for sid in ("summary", "edges", "star", "bars", "wedges", "niirs"):
        assert html.index(f'<h2 id="{sid}">') < gallery
    for caption in ("Slanted edge edge_act:", "Siemens star star:", "Bar target bars:", "Wedge wedge_h:"):
        assert html.index(caption) < gallery  # the measured-vs-predicted figures come first
    # every target thumbnail carries its region overlay
    thumbs = re.findall(r'<span class="ovwrap">(.*?)</span>', html, flags=re.S)
    assert len(thumbs) == html.count('<details class="zoom">')
    by_alt = {re.search(r'alt="([^"]+)"', t).group(1): t for t in thumbs}
    assert "Nyquist (r = " in by_alt["star, detector"] and "measured annulus" in by_alt["star, detector"]
    assert "edge fit" in by_alt["edge_act, detector"] and "scan, wide end first" in by_alt["wedge_h, detector"]
    bars = by_alt["bars, detector"]
    gsd = run.res["gsd_m"]
    measured = [round(gsd / f, 6) for f in run.res["bar_targets"][0]["f_cy_per_px"]]
    labels = re.findall(r">([\d.]+) m</text><text[^>]*>([a-z ]+)<", bars)
    assert [float(p) for p, _ in labels] == [4.0, 3.0, 2.0, 1.5]  # the groups of BARS_TOML, each labelled
    for p, word in labels:
        p = float(p)
        if round(p, 6) not in measured:
            assert word == "not measured"
        else:
            assert word == ("compared" if gsd / p <= BAR_COMPARE_MAX_CY_PER_PX else "not compared")


def test_page_weight_and_micrometres(run):
    assert len(run.html.encode()) <= 2.5e6  # issue 18: at most 2.5 MB (the default run's is measured in the PR)
    text = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", run.html)
    assert not re.search(r"\d\s?um\b|\(um\)|\bum\^|\bum\$", text), "micrometres are µm"
    assert "µm" in text


def test_figures_are_palette_pngs(run):
    """The report's figures are quantised to a palette (a third of the RGBA weight)."""
    for png in _images(run.html)[:10]:
        with Image.open(io.BytesIO(png)) as im:
            assert im.mode in ("P", "L"), im.mode


def test_bars_show_raw_and_corrected_ctf_with_the_correction_stated(run):
    (b,) = run.res["bar_targets"]
    raw, ctf, corr = (np.array(b[k], float) for k in ("ctf_raw_measured", "ctf_measured", "ctf_correction"))
    ok = np.isfinite(corr)
    np.testing.assert_allclose(raw[ok] + corr[ok], ctf[ok], atol=1e-12)
    lo = run.html.index('<h2 id="bars">')
    section = run.html[lo : run.html.index("<h2 ", lo + 1)]
    assert "square-wave correction" in section and "CTF raw" in section and "CTF corrected" in section
    if ok.any() and np.any(corr[ok] != 0):
        assert "correction ranges from" in section
    rows = _read_csv(run.out / "curves" / "bars_ctf.csv")
    assert {"ctf_raw_measured", "ctf_measured", "ctf_correction_square_wave", "ctf_std_measured"} <= set(rows[0])


def test_printed_differences_keep_the_sign_of_the_error(run):
    """Every signed difference in the summary table has the sign of results.json's error (NIIRS -0.0039 was
    printed "+0.00")."""
    checked = 0
    for r in run.res["summary"]:
        if r["kind"] == "niirs":
            pattern = r'data-label="">NIIRS \(GIQE 5\)</td>.*?data-label="difference">([^<]*)<'
        elif r["kind"] == "edge_mtf_at_nyquist":
            pattern = rf'slanted edge {r["id"]}(?: · <a [^>]*>[^<]*</a>)?</td>.*?data-label="difference">([^<]*)<'
        else:
            continue
        text = re.search(pattern, run.html, flags=re.S).group(1)
        if r["error"]:
            assert text[0] == ("-" if r["error"] < 0 else "+") and float(text.split()[0]) != 0, (r, text)
            checked += 1
    assert checked >= 3


def test_summary_table_marks_a_tolerance_inside_the_noise():
    from satchain.report import tables

    res = {
        "tolerances": {"edge_mtf_at_nyquist": 0.004},
        "slanted_edges": [{"id": "e", "direction": "ACT", "mtf_at_nyquist_measured": 0.2069,
                           "mtf_at_nyquist_predicted": 0.1983, "pass": False, "flags": ["low_cnr"]}],
        "summary": [{"kind": "edge_mtf_at_nyquist", "id": "e", "error": 0.0086, "sigma": 0.0038, "z": 2.26,
                     "tolerance_value": 0.004, "tolerance_inside_noise": True, "pass": False}],
    }  # fmt: skip
    (row,) = tables.summary_rows(res)
    assert row["noise"] is True and row["sigma"] == "0.0038" and row["z"] == "+2.3" and row["n_flags"] == 1
    res["summary"][0].update(sigma=None, z=None, tolerance_inside_noise=None, sigma_null_means="no MTF sigma")
    (row,) = tables.summary_rows(res)
    assert row["noise"] is False and row["sigma"] == "–" and row["sigma_note"] == "no MTF sigma"
