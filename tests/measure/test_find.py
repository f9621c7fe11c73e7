"""Automatic slanted-edge detection and the combined ACT / ALT MTF, on charts rendered independently
(_render_chart.py: dark rotated squares, anisotropic Gaussian x square-pixel blur, exact ESF per side)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _render_chart import expected_edges, render_chart, true_mtf
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.ndimage import gaussian_filter
from scipy.special import erf

from satchain.errors import InputError
from satchain.measure.find import find_edges
from satchain.measure.find_mtf import ceos_table, measure_found_edges

SX, SY = 0.45, 0.6  # Gaussian PSF sigma (px) along x (ACT) and y (ALT)
SQUARES = [(100.3, 100.0, 100, 5.0), (300.0, 100.6, 100, 8.0), (100.0, 300.2, 100, -6.0), (299.7, 300.0, 100, 7.0)]


@pytest.fixture(scope="module")
def chart():
    return render_chart((400, 400), SQUARES, sx=SX, sy=SY, noise=0.004, rng=np.random.default_rng(3))


@pytest.fixture(scope="module")
def chart_result(chart):
    return measure_found_edges(chart)


def _match(candidates, truth):
    """For every truth side, the candidate whose centre lies within 3 px of the side's midpoint line."""
    out = []
    for px, py, ang, direction in truth:
        t = np.deg2rad(ang)
        ux, uy = np.sin(t), np.cos(t)
        best = [
            c
            for c in candidates
            if abs((c.center_xy[0] - px) * uy - (c.center_xy[1] - py) * ux) < 3
            and np.hypot(c.center_xy[0] - px, c.center_xy[1] - py) < 20
        ]
        out.append((ang, direction, best))
    return out


def test_chart_finds_every_side_with_its_angle_and_direction(chart):
    s = find_edges(chart)
    truth = expected_edges(SQUARES)
    assert len(s) == len(truth) == 16
    for ang, direction, found in _match(s.candidates, truth):
        assert len(found) == 1, (ang, found)
        c = found[0]
        assert abs(c.angle_deg - ang) < 0.5
        assert c.direction == direction
        x0, y0, x1, y1 = c.roi
        assert x1 - x0 >= 30 and y1 - y0 >= 30


def test_chart_combined_mtf_at_nyquist_matches_truth(chart_result):
    res = chart_result
    for d, sigma in (("ACT", SX), ("ALT", SY)):
        c = res.combined[d]
        truth = float(true_mtf(0.5, sigma))
        assert c.n_edges == 8
        assert abs(c.mtf_at_nyquist - truth) < 0.02
        assert 0 < c.mtf_at_nyquist_sigma < 0.02
        # the reported sigma is honest: the truth lies within 3 sigma
        assert abs(c.mtf_at_nyquist - truth) < 3 * c.mtf_at_nyquist_sigma
        band = c.f_cy_per_px <= 0.6
        assert np.max(np.abs(c.mtf[band] - true_mtf(c.f_cy_per_px[band], sigma))) < 0.03
    assert not res.flags
    for e in res.edges:
        assert e.mtf_at_nyquist_sigma > 0


def test_ceos_table_steps_and_values(chart_result):
    t = ceos_table(chart_result)
    assert t["f_over_fs"].size == 27  # 0, 0.02, ..., 0.5 and the CEOS row 0.25 (half Nyquist)
    assert np.allclose(np.diff(t["f_over_fs"][t["f_over_fs"] != 0.25]), 0.02)
    assert 0.25 in t["f_over_fs"]
    assert t["f_over_fs"][-1] == pytest.approx(0.5)
    assert t["mtf_act"][0] == pytest.approx(1.0) and t["mtf_alt"][0] == pytest.approx(1.0)
    assert np.all(np.abs(t["mtf_act"] - true_mtf(t["f_over_fs"], SX)) < 0.03)
    assert np.all(np.abs(t["mtf_alt"] - true_mtf(t["f_over_fs"], SY)) < 0.03)
    assert np.all(t["mtf_act_sigma"][1:] > 0) and np.all(t["mtf_alt_sigma"][1:] > 0)
    assert t["mtf_act_sigma"][0] == 0 and t["mtf_alt_sigma"][0] == 0  # MTF(0) = 1 by normalisation
    t1 = ceos_table(chart_result, f_max=1.0)
    assert t1["f_over_fs"].size == 52


def test_json_round_trip(chart_result):
    d = json.loads(json.dumps(chart_result.to_dict(), allow_nan=False))
    assert set(d["combined"]) == {"ACT", "ALT"}
    assert len(d["edges"]) == 16


def test_banding_does_not_change_the_result(chart):
    a = find_edges(chart, band_rows=512)
    b = find_edges(chart, band_rows=64)
    assert [c.roi for c in a] == [c.roi for c in b]
    assert np.allclose([c.angle_deg for c in a], [c.angle_deg for c in b])


@pytest.mark.parametrize(
    "image, reason",
    [
        (np.full((300, 300), 0.4), "no straight"),
        (np.random.default_rng(0).normal(0.5, 0.05, (300, 300)), "no straight"),
    ],
)
def test_blank_and_noise_are_refused(image, reason):
    with pytest.raises(InputError, match=reason):
        measure_found_edges(image)


def test_axis_aligned_squares_are_refused_with_the_reason():
    img = render_chart((300, 300), [(80, 80, 90, 0.0), (210, 200, 90, 0.0)], sx=SX, sy=SY, noise=0.003)
    with pytest.raises(InputError, match="axis-aligned: 8"):
        measure_found_edges(img)


def test_thin_bar_is_not_isolated():
    # a 7 px wide dark bar: its two edges sit inside each other's ROI
    bar = render_chart((240, 240), [(120, 120, 160, 6.0)], sx=SX, sy=SY)
    yy, xx = np.mgrid[0:240, 0:240]
    t = np.deg2rad(6.0)
    d = (xx - 120) * np.cos(t) - (yy - 120) * np.sin(t)
    stripe = np.where(np.abs(d) < 3.5, 0.15, 0.85)
    stripe = gaussian_filter(stripe, 0.7, mode="nearest")
    s = find_edges(stripe)
    assert len(s) == 0
    assert s.rejection_counts().get("not isolated", 0) >= 1
    assert len(find_edges(bar)) == 4  # control: the same edges far apart are found


def test_one_direction_only_is_flagged():
    yy, xx = np.mgrid[0:300, 0:200]
    t = np.deg2rad(5.0)
    d = (xx - 100.2) * np.cos(t) - (yy - 150) * np.sin(t)
    img = 0.2 + 0.6 * 0.5 * (1 + erf(d / (np.sqrt(2) * 0.7)))
    res = measure_found_edges(img)
    assert set(res.combined) == {"ACT"}
    assert any("no usable ALT edge" in f for f in res.flags)
    assert any("single edge" in f for f in res.combined["ACT"].flags)
    assert np.all(np.isnan(ceos_table(res)["mtf_alt"]))


def test_disagreeing_edges_are_flagged():
    sq = [(100, 100, 100, 5.0), (100, 300, 100, 7.0)]
    sharp = render_chart((400, 200), sq, sx=0.4, sy=0.5, noise=0.002, rng=np.random.default_rng(1))
    soft = render_chart((400, 200), sq, sx=0.9, sy=0.5, noise=0.002, rng=np.random.default_rng(2))
    res = measure_found_edges(np.hstack([sharp, soft]))
    act = res.combined["ACT"]
    assert act.chi2_reduced_at_nyquist > 5
    assert any("disagree" in f for f in act.flags)
    # Birge inflation: the reported sigma covers the spread between the two halves
    assert act.mtf_at_nyquist_sigma > 0.5 * act.scatter_at_nyquist / np.sqrt(act.n_edges)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rot=st.floats(2.0, 40.0), dx=st.floats(0.0, 1.0), dy=st.floats(0.0, 1.0))
def test_any_rotation_and_offset(rot, dx, dy):
    sq = [(130 + dx, 130 + dy, 120, rot)]
    img = render_chart((260, 260), sq, sx=0.5, sy=0.5, noise=0.003, rng=np.random.default_rng(7))
    s = find_edges(img)
    truth = expected_edges(sq)
    assert len(s) == 4
    assert sorted(c.direction for c in s) == ["ACT", "ACT", "ALT", "ALT"]
    for ang, direction, found in _match(s.candidates, truth):
        assert len(found) == 1
        assert abs(found[0].angle_deg - ang) < 0.5
        assert found[0].direction == direction


def test_cli_find_writes_json_csv_png(chart, tmp_path):
    from typer.testing import CliRunner

    from satchain.cli.main import app

    np.save(tmp_path / "chart.npy", chart)
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["measure", "find", str(tmp_path / "chart.npy"), "--json", "-o", str(out)])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["combined"]["ACT"]["n_edges"] == 8
    assert {p.name for p in out.iterdir()} == {"find.json", "find_ceos.csv", "find.png"}
    rows = (out / "find_ceos.csv").read_text().splitlines()
    assert rows[0] == "f_over_fs,mtf_act,mtf_act_sigma,mtf_alt,mtf_alt_sigma"
    assert len(rows) == 28 and any(r.startswith("0.25,") for r in rows)
    last = [float(v) for v in rows[-1].split(",")]
    assert last[0] == 0.5 and abs(last[1] - true_mtf(0.5, SX)) < 0.02 and abs(last[3] - true_mtf(0.5, SY)) < 0.02


def test_cli_find_refuses_blank_image_with_exit_2(tmp_path):
    from typer.testing import CliRunner

    from satchain.cli.main import app

    np.save(tmp_path / "blank.npy", np.full((200, 200), 0.3))
    r = CliRunner().invoke(app, ["measure", "find", str(tmp_path / "blank.npy")])
    assert r.exit_code == 2
    assert "no usable slanted edge" in r.output


def test_integer_image_and_saturated_edges():
    img = render_chart((300, 300), [(150.2, 150.1, 140, 6.0)], sx=0.5, sy=0.5, noise=0.003)
    truth = float(true_mtf(0.5, 0.5))
    res = measure_found_edges(np.round(img * 40000).astype(np.uint16))
    for d in ("ACT", "ALT"):
        assert abs(res.combined[d].mtf_at_nyquist - truth) < 0.02
    clipped = np.clip(np.round(img * 1.3 * 65535), 0, 65535).astype(np.uint16)  # bright side saturated
    with pytest.raises(InputError, match="measurement refused: 4.*saturat"):
        measure_found_edges(clipped)


@pytest.mark.parametrize("gap_px, n_found", [(14, 6), (20, 8), (40, 8)])
def test_close_neighbours_narrow_the_roi_or_reject(gap_px, n_found):
    # two squares whose facing ACT sides are gap_px apart: a 16 px half-width ROI would hold both edges
    sq = [(80, 120, 100, 5.0), (180 + gap_px, 120, 100, 5.0)]
    img = render_chart((240, 320), sq, sx=0.5, sy=0.5, noise=0.003, rng=np.random.default_rng(5))
    s = find_edges(img)
    assert len(s) == n_found
    assert s.rejection_counts().get("not isolated", 0) == 8 - n_found
    res = measure_found_edges(img, search=s)
    truth = float(true_mtf(0.5, 0.5))
    for c in res.combined.values():
        assert abs(c.mtf_at_nyquist - truth) < 0.02


@pytest.mark.parametrize("opt, val", [("--min-length", "5"), ("--max-edges", "0"), ("--f-max", "1.5")])
def test_cli_find_bad_options_exit_2(tmp_path, opt, val):
    from typer.testing import CliRunner

    from satchain.cli.main import app

    np.save(tmp_path / "x.npy", np.zeros((64, 64)))
    r = CliRunner().invoke(app, ["measure", "find", str(tmp_path / "x.npy"), opt, val])
    assert r.exit_code == 2
    assert opt in r.output


def test_mtf_near_zero_at_nyquist_is_flagged_as_upper_bound():
    sq = [(100, 100, 100, 5.0), (100, 300, 100, 7.0)]
    img = render_chart((400, 200), sq, sx=1.5, sy=1.5, noise=0.01, rng=np.random.default_rng(4))
    res = measure_found_edges(img)
    for c in res.combined.values():
        assert any("upper bound" in f for f in c.flags)
        assert c.mtf_at_nyquist >= 0
