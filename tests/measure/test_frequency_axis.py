"""MTF on MTF_Estimator's frequency axis (``frequency_axis="row"``, issue 19).

MTF_Estimator (FidMTF) projects the pixels on the image row: for an edge tilted by ``t`` from the nearest pixel
axis the row distance is ``x = d / cos t`` (``d`` along the normal), so the row ESF is ``E(x cos t)`` and

    MTF_row(f) = MTF_normal(f / cos t)     (the row axis is the normal one scaled by cos t).

The edge is rendered here exactly: a Gaussian-blurred straight edge integrated over each pixel by ``S x S``
midpoint samples, whose MTF along the normal is ``exp(-2 pi^2 s^2 f^2) D(f cos t) D(f sin t)`` with the
sampled aperture ``D(u) = sin(pi u) / (S sin(pi u / S))``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.special import ndtr
from typer.testing import CliRunner

from satchain.errors import InputError
from satchain.measure.edge import measure_edge
from satchain.measure.find_mtf import measure_found_edges

BLUR = 0.6  # px
SUB = 8


def _render(angle_deg: float, n: int = 96) -> np.ndarray:
    t = np.deg2rad(angle_deg)
    o = (np.arange(SUB) + 0.5) / SUB - 0.5
    y, x = np.mgrid[0:n, 0:n].astype(float)
    acc = sum(ndtr(((x + dx - n / 2) * np.cos(t) - (y + dy - n / 2) * np.sin(t)) / BLUR) for dx in o for dy in o)
    return 0.1 + 0.8 * acc / SUB**2


def _aperture(u):
    u = np.asarray(u, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.sin(np.pi * u) / (SUB * np.sin(np.pi * u / SUB))
    return np.abs(np.where(np.abs(u) < 1e-12, 1.0, d))


def truth_normal(f, angle_deg: float):
    t = np.deg2rad(angle_deg)
    f = np.asarray(f, dtype=float)
    return np.exp(-2 * np.pi**2 * BLUR**2 * f**2) * _aperture(f * np.cos(t)) * _aperture(f * np.sin(t))


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(angle=st.floats(3.0, 40.0), transpose=st.booleans())
def test_row_axis_is_the_normal_axis_scaled_by_cos_tilt(angle, transpose):
    img = _render(angle)
    img = img.T if transpose else img  # an ALT edge: its row axis is the image column
    rn = measure_edge(img)
    rr = measure_edge(img, frequency_axis="row")
    assert rn.direction == rr.direction == ("ALT" if transpose else "ACT")
    c = np.cos(np.deg2rad(angle))
    assert rn.frequency_axis == "normal" and rn.frequency_scale == 1.0
    assert rr.frequency_axis == "row" and rr.frequency_scale == pytest.approx(c, abs=2e-4)
    f = rr.f_cy_per_px
    band = f <= 0.6
    # each curve against the exact MTF on its own axis
    assert (
        np.max(np.abs(rn.mtf[rn.f_cy_per_px <= 0.6] - truth_normal(rn.f_cy_per_px[rn.f_cy_per_px <= 0.6], angle)))
        < 0.01
    )
    assert np.max(np.abs(rr.mtf[band] - truth_normal(f[band] / c, angle))) < 0.01
    assert rr.mtf_at_nyquist == pytest.approx(float(truth_normal(0.5 / c, angle)), abs=0.01)
    # and against each other: MTF_row(f cos t) = MTF_normal(f)
    np.testing.assert_allclose(np.interp(rn.f_cy_per_px[:80] * c, f, rr.mtf), rn.mtf[:80], atol=2e-3)
    if rn.mtf50_cy_per_px is not None:
        assert rr.mtf50_cy_per_px == pytest.approx(rn.mtf50_cy_per_px * c, rel=0.01)
    assert rr.mtf_at_nyquist <= rn.mtf_at_nyquist  # a falling MTF: lower at Nyquist on the row axis


def test_baotou_tilt_scales_the_axis_by_4_percent():
    rr = measure_edge(_render(16.8), frequency_axis="row")
    assert 1 - rr.frequency_scale == pytest.approx(1 - np.cos(np.deg2rad(16.8)), abs=2e-4)  # 0.043
    assert rr.f_cy_per_m_ground is None
    g = measure_edge(_render(16.8), frequency_axis="row", pixel_m=0.5)
    np.testing.assert_allclose(g.f_cy_per_m_ground, g.f_cy_per_px / 0.5)  # cy/m along the row


def test_find_on_the_row_axis():
    img = _render(8.0, n=120)
    rn, rr = measure_found_edges(img), measure_found_edges(img, frequency_axis="row")
    c = np.cos(np.deg2rad(8.0))
    assert rr.frequency_axis == "row" and rr.edges[0].frequency_scale == pytest.approx(c, abs=2e-4)
    assert rr.combined["ACT"].mtf_at_nyquist == pytest.approx(float(truth_normal(0.5 / c, 8.0)), abs=0.01)
    assert rn.combined["ACT"].mtf_at_nyquist == pytest.approx(float(truth_normal(0.5, 8.0)), abs=0.01)


def test_bad_axis_is_refused():
    with pytest.raises(InputError, match="frequency_axis = 'column'"):
        measure_edge(_render(5.0), frequency_axis="column")


@pytest.mark.parametrize("command", ["edge", "find"])
def test_cli_frequency_axis(tmp_path, command):
    from satchain.cli.measure import measure_app

    path = tmp_path / "edge.npy"
    np.save(path, _render(16.8, n=100))
    runner = CliRunner()
    r = runner.invoke(measure_app, [command, str(path), "--frequency-axis", "row", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    scale = d["frequency_scale"] if command == "edge" else d["edges"][0]["frequency_scale"]
    assert d["frequency_axis"] == "row" and scale == pytest.approx(np.cos(np.deg2rad(16.8)), abs=2e-4)
    out = runner.invoke(measure_app, [command, str(path), "--frequency-axis", "row"]).stdout
    assert "MTF_Estimator" in out and "0.957" in out
    bad = runner.invoke(measure_app, [command, str(path), "--frequency-axis", "diagonal"])
    assert bad.exit_code == 2 and "--frequency-axis" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1
