"""The page of a design study (``DIR/study.html``): self-contained, one plot per figure x axis, a map per figure
with two axes, the case table's links and escaping, a large budget study, and an atomic write."""

from __future__ import annotations

import base64
import io
import itertools
import os
import re
from html.parser import HTMLParser

import numpy as np
import pytest
from PIL import Image

from satchain.errors import ConfigError
from satchain.report import study_page
from satchain.report.study_page import write_study_page

A, W = "optics.aperture_diameter_m", "optics.wfe_rms_waves"
APERTURES, WFES = [0.35, 0.45, 0.55, 0.70], [0.0, 0.05, 0.10]
WEDGE, EDGE, EMPTY = "wedge wedge_h resolution (m, ALT)", "edge edge_act MTF@Nyquist (ACT)", "niirs"
GSD_M = 0.49
#: Each repeat's measured offset from the prediction (closed form: its mean over repeats is 0.01).
OFFSET = {1: 0.005, 2: 0.015}
ERROR_CASE, FAILED_CASE = "c0006", "c0009"
MESSAGE = "simulate: <script>alert('x')</script> & more"


def wedge_m(a: float, w: float) -> float:
    return GSD_M * (1 + 0.2 * (0.5 / a) ** 2 * (1 + 10 * w))


def edge_mtf(a: float, w: float) -> float:
    return 0.3 - 0.2 * a - w


def base_row(**kw) -> dict:
    row = {"case": "c0001", "repeat": 1, "seed": 1, "case_status": "ok", "message": None, "figure": None,
           "kind": None, "check_id": None, "unit": "", "measured": None, "predicted": None, "error": None,
           "sigma": None, "z": None, "pass": None, "gsd_m": GSD_M, "q": 1.2, "mtf_at_nyquist_act": 0.1,
           "mtf_at_nyquist_alt": 0.1, "snr": 80.0, "niirs": 4.5, "folder": None, "report": None}  # fmt: skip
    row.update(kw)
    return row


def run_rows(*, one_axis: bool = False) -> tuple[list[dict], dict]:
    """A run-depth study over aperture x WFE (or aperture only), 2 repeats; c0006 raised, c0009 failed a check;
    the odd cases kept their report."""
    axes = {A: APERTURES} if one_axis else {A: APERTURES, W: WFES}
    rows = []
    for i, vals in enumerate(itertools.product(*axes.values())):
        a, w = vals[0], (vals[1] if len(vals) > 1 else 0.0)
        cid = f"c{i + 1:04d}"
        common = dict(zip(axes, vals, strict=True), case=cid, folder=f"cases/{cid}",
                      report=f"cases/{cid}/report.html" if i % 2 == 0 else None)  # fmt: skip
        if cid == ERROR_CASE:
            rows.append(base_row(**common, seed=100 * i, case_status="error", message=MESSAGE))
            continue
        status = "failed" if cid == FAILED_CASE else "ok"
        for rep in (1, 2):
            c = dict(common, repeat=rep, seed=100 * i + rep, case_status=status)
            p = wedge_m(a, w)
            rows.append(base_row(**c, figure=WEDGE, kind="wedge_resolution", check_id="wedge_h", unit="m",
                                 measured=p + OFFSET[rep], predicted=p, sigma=0.004, **{"pass": True}))  # fmt: skip
            rows.append(base_row(**c, figure=EDGE, kind="edge_mtf_at_nyquist", check_id="edge_act",
                                 measured=edge_mtf(a, w) + OFFSET[rep], predicted=edge_mtf(a, w),
                                 **{"pass": cid != FAILED_CASE}))  # fmt: skip
            rows.append(base_row(**c, figure=EMPTY, kind="niirs"))  # no value: skipped
    return rows, axes


class Page(HTMLParser):
    """What a page holds: images, links, figures (class, data-figure, data-axis), table rows."""

    def __init__(self, text: str):
        super().__init__()
        self.imgs: list[str] = []
        self.hrefs: list[str] = []
        self.tags: set[str] = set()
        self.figures: list[tuple[str, str | None, str | None]] = []
        self.case_links: dict[str, set[str]] = {}
        self._href: str | None = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.add(tag)
        if tag == "img":
            self.imgs.append(a["src"])
        elif tag == "a":
            self.hrefs.append(a["href"])
            self._href = a["href"]
        elif tag == "figure":
            self.figures.append((a.get("class"), a.get("data-figure"), a.get("data-axis")))
        for k in ("src", "href"):
            if k in a and tag not in ("img", "a"):
                self.hrefs.append(a[k])

    def handle_data(self, data):
        if self._href is not None:
            self.case_links.setdefault(data, set()).add(self._href)
            self._href = None

    def plots(self) -> list[tuple[str | None, str | None]]:
        return [(f, ax) for c, f, ax in self.figures if c == "plot"]

    def maps(self) -> list[str | None]:
        return [f for c, f, _ in self.figures if c == "map"]


@pytest.fixture(scope="module")
def run_page(tmp_path_factory) -> tuple[str, Page]:
    rows, axes = run_rows()
    path = tmp_path_factory.mktemp("study") / "study.html"
    out = write_study_page(path, rows, axes=axes, depth="run", held_fixed=["aperture: focal length held fixed"],
                           findings=[("Detector limited", "up to <0.45 m>")])  # fmt: skip
    assert out == path
    text = path.read_text()
    return text, Page(text)


def test_the_page_is_one_self_contained_file(run_page):
    text, page = run_page
    assert page.imgs and all(s.startswith("data:image/png;base64,") for s in page.imgs)
    for src in page.imgs:  # every embedded figure decodes as a PNG
        with Image.open(io.BytesIO(base64.b64decode(src.split(",", 1)[1]))) as im:
            assert im.format == "PNG" and im.size[0] > 300
    assert not {"link", "script", "iframe", "object"} & page.tags
    assert "http" not in " ".join(page.hrefs) and 'src="http' not in text
    assert all(h.startswith("cases/c") for h in page.hrefs)  # only the cases' own files


def test_one_plot_per_figure_and_axis_and_a_map_per_figure(run_page):
    _, page = run_page
    expected = set(itertools.product([WEDGE, EDGE], [A, W]))
    assert sorted(page.plots()) == sorted(expected)  # each once
    assert sorted(page.maps()) == sorted([WEDGE, EDGE])


def test_a_figure_without_any_value_is_skipped(run_page):
    text, page = run_page
    assert EMPTY not in {f for f, _ in page.plots()} | set(page.maps())
    assert re.search(r'class="note skipped">[^<]*niirs', text)


def test_one_axis_plots_without_maps(tmp_path):
    rows, axes = run_rows(one_axis=True)
    page = Page(write_study_page(tmp_path / "s.html", rows, axes=axes, depth="run").read_text())
    assert sorted(page.plots()) == sorted([(WEDGE, A), (EDGE, A)])
    assert page.maps() == []


def test_case_table_links_reports_else_results_json_and_escapes_messages(run_page):
    text, page = run_page
    rows, _ = run_rows()
    for i in range(len(APERTURES) * len(WFES)):
        cid = f"c{i + 1:04d}"
        want = f"cases/{cid}/report.html" if i % 2 == 0 else f"cases/{cid}/results.json"
        assert page.case_links[cid] == {want}
    n_runs = len({(r["case"], r["repeat"]) for r in rows})
    assert text.count('<tr><td class="l"><a href=') == n_runs == 2 * 12 - 1
    assert "<script>" not in text and "&lt;script&gt;alert(" in text and "&amp; more" in text
    assert "up to &lt;0.45 m&gt;" in text  # findings escaped too
    counts = re.search(r'<p class="counts">(.*?)</p>', text, re.S)
    assert counts is not None
    assert re.sub(r"<[^>]+>|\s+", " ", counts.group(1)).split() == \
        "12 cases (23 runs with repeats): 10 ok · 1 failed · 1 error".split()  # fmt: skip


def test_the_gsd_line_by_default_and_figure_lines_added(tmp_path):
    rows, axes = run_rows(one_axis=True)
    text = write_study_page(tmp_path / "s.html", rows, axes=axes, depth="run", figure_lines={EDGE: "q"}).read_text()
    caps = dict(re.findall(r'data-figure="([^"]+)" data-axis="[^"]+">.*?<figcaption>(.*?)</figcaption>', text))
    assert "dashed: GSD" in caps[WEDGE] and "dashed: Q" in caps[EDGE]
    with pytest.raises(ConfigError, match="no_such_column"):
        write_study_page(tmp_path / "t.html", rows, axes=axes, depth="run", figure_lines={EDGE: "no_such_column"})


def test_grid_averages_repeats_and_leaves_the_error_case_empty():
    rows, axes = run_rows()
    series, _ = study_page._series(rows, list(axes), "run", {})
    wedge = next(s for s in series if s.name == WEDGE)
    xs, ys, z = study_page._grid(wedge, list(axes), axes, wedge.measured)
    assert np.allclose(xs, APERTURES) and np.allclose(ys, WFES)
    want = np.array([[wedge_m(a, w) + 0.01 for a in APERTURES] for w in WFES])  # mean offset 0.01
    want[WFES.index(0.10), APERTURES.index(0.45)] = np.nan  # c0006 raised
    np.testing.assert_allclose(z, want, rtol=1e-12)


def test_prediction_lines_per_combination_sorted_and_averaged():
    rows, axes = run_rows()
    series, _ = study_page._series(rows, list(axes), "run", {})
    wedge = next(s for s in series if s.name == WEDGE)
    combo, values = study_page._combinations(wedge, [W])
    polys, which = study_page._lines(combo, wedge.x[A], wedge.measured)
    assert np.allclose(values[:, 0], WFES) and list(which) == [0, 1, 2]
    for poly, w in zip(polys, WFES, strict=True):
        aps = [a for a in APERTURES if not (a == 0.45 and w == 0.10)]
        np.testing.assert_allclose(poly[:, 0], aps)
        np.testing.assert_allclose(poly[:, 1], [wedge_m(a, w) + 0.01 for a in aps], rtol=1e-12)


def budget_rows(n1: int, n2: int) -> tuple[list[dict], dict]:
    axes = {A: list(np.linspace(0.3, 0.8, n1)), W: list(np.linspace(0.0, 0.1, n2))}
    figures = ["niirs", "rer", "rer_act", "rer_alt", "snr", "mtf_nyquist_act", "mtf_nyquist_alt", "gsd_m", "q"]
    rows = []
    for i, (a, w) in enumerate(itertools.product(*axes.values())):
        for j, f in enumerate(figures):
            rows.append(base_row(**{A: a, W: w}, case=f"c{i + 1:04d}", seed=i, figure=f, kind="budget",
                                 predicted=j + 2 * a - 3 * w))  # fmt: skip
    return rows, axes


def test_a_thousand_budget_cases_render(tmp_path):
    rows, axes = budget_rows(40, 25)
    text = write_study_page(tmp_path / "study.html", rows, axes=axes, depth="budget").read_text()
    page = Page(text)
    assert len(page.plots()) == 9 * 2 and len(page.maps()) == 9
    assert len(page.imgs) == 27 and 'class="grid compact"' in text
    assert text.count('<tr><td class="l">c') == 1000  # no folder: the ids are not links
    assert page.hrefs == [] and "measured ± 1σ" not in text


def test_a_failed_write_leaves_the_page_as_it_was(tmp_path, monkeypatch):
    rows, axes = run_rows()
    path = tmp_path / "study.html"

    def boom(*args, **kwargs):
        raise RuntimeError("drawing failed")

    monkeypatch.setattr(study_page, "_map_png", boom)
    with pytest.raises(RuntimeError, match="drawing failed"):
        write_study_page(path, rows, axes=axes, depth="run")
    assert os.listdir(tmp_path) == []
    path.write_text("the earlier page")
    with pytest.raises(RuntimeError, match="drawing failed"):
        write_study_page(path, rows, axes=axes, depth="run")
    assert os.listdir(tmp_path) == ["study.html"] and path.read_text() == "the earlier page"


def test_bad_arguments_name_the_parameter(tmp_path):
    rows, axes = run_rows(one_axis=True)
    with pytest.raises(ConfigError, match="depth = 'deep'"):
        write_study_page(tmp_path / "s.html", rows, axes=axes, depth="deep")
    with pytest.raises(ConfigError, match="optics.focal_length_m"):
        write_study_page(tmp_path / "s.html", rows, axes={**axes, "optics.focal_length_m": [1.0]}, depth="run")
    assert not (tmp_path / "s.html").exists()
