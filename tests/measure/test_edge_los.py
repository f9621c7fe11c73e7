"""Line-of-sight motion in a slanted edge (issue 29, item 11): the MTF with each line located (``mtf_aligned``,
the budget's per-row motion terms) and as imaged (``mtf_as_imaged``, ISO 12233's straight fit with the lines'
displacements folded in), with the motion removed (``los_motion_rms_px``) and the ``line_of_sight_motion`` flag.

Images: exact time-domain TDI renders (:mod:`_render_tdi`, each row the mean over its window of the static
render at the path's position); the truth factors come from the same path, computed here.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from _render_tdi import motion_factors, render_tdi_edge
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from satchain import load_preset
from satchain.measure.edge import measure_edge
from satchain.tf.pushbroom import PushbroomTerms, oscillation_otf

SYSTEM = load_preset("ankarasat3")
DT, N = SYSTEM.line_time_s, SYSTEM.detector.tdi_stages  # line time (s) and TDI stages: the window T = N dt
ANGLE = 5.0
NU = 0.5 * np.cos(np.radians(ANGLE))  # Nyquist along the normal, seen along the row (the motion's axis)
TOL = 0.03  # at Nyquist, noise-free


def _pair(n, path):
    width = int(36 + n * np.tan(np.radians(ANGLE)))
    kw = dict(angle_deg=ANGLE, x0=18.3, line_time_s=DT, stages=N, blur_px=0.35)
    moving = measure_edge(render_tdi_edge(n, width, **path, **kw))
    still = path | {"amp_px": [0.0] * len(path["amp_px"])}
    return moving, measure_edge(render_tdi_edge(n, width, **still, **kw))


def _check(r, static, n, path):
    per_row, imaged = motion_factors(np.array([0.5]), ANGLE, n_lines=n, line_time_s=DT, stages=N, **path)
    assert "line_of_sight_motion" in r.flags
    assert r.los_motion_rms_px > 0.1
    assert abs(r.mtf_aligned[100] - static.mtf_at_nyquist * per_row[0]) < TOL
    assert abs(r.mtf_as_imaged_at_nyquist - static.mtf_at_nyquist * imaged[0]) < TOL
    assert r.mtf_at_nyquist == r.mtf_aligned[100]  # the headline is the aligned MTF (fit_degree "auto")


@pytest.mark.parametrize("cycles", [0.3, 0.5])
@pytest.mark.parametrize("phase_deg", [0.0, 90.0])
def test_oscillation_non_whole_cycles_aligned_and_as_imaged(cycles, phase_deg):
    """ACT 1 px, 0.3 / 0.5 cycles per TDI window at phases 0 and 90 deg (the issue's -0.41..+0.38 swings)."""
    path = {"amp_px": [1.0], "freq_hz": [cycles / (N * DT)], "phase_rad": [np.radians(phase_deg)]}
    r, static = _pair(100, path)
    _check(r, static, 100, path)
    budget = static.mtf_at_nyquist * float(oscillation_otf(NU, amplitude_px=1.0, cycles_per_window=cycles))
    assert abs(r.mtf_at_nyquist - budget) < TOL  # the budget's per-row term
    osc = {"axis": "act", "amplitude_px": 1.0, "frequency_hz": cycles / (N * DT), "phase_deg": phase_deg}
    terms = PushbroomTerms(SYSTEM.replace({"motion.oscillation": [osc]}))
    assert abs(abs(terms.per_row_otf(NU, "act")[0]) * static.mtf_at_nyquist - r.mtf_aligned[100]) < TOL
    imaged = terms.as_imaged_otf(NU, "act", first_line=0, n_lines=100)[0] * static.mtf_at_nyquist
    assert abs(r.mtf_as_imaged_at_nyquist - imaged) < TOL  # the budget's prediction as imaged, over the ROI


def test_jitter_band_50_800_hz():
    """A 50-800 Hz band of 1 px rms (40 sinusoids, random phases): measured 0.062 against 0.134 before."""
    rng = np.random.default_rng(3)
    f = np.linspace(50.0, 800.0, 40)
    path = {"amp_px": [np.sqrt(2.0 / 40)] * 40, "freq_hz": list(f), "phase_rad": list(rng.uniform(0, 2 * np.pi, 40))}
    r, static = _pair(200, path)
    _check(r, static, 200, path)
    assert r.mtf_as_imaged_at_nyquist < r.mtf_aligned[100]  # the lines' displacements folded in blur further


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    f_hz=st.floats(80.0, 160.0), n=st.sampled_from([400, 800]), amp=st.sampled_from([0.5, 1.0, 2.0]),
    phase=st.floats(0.0, 2 * np.pi),
)  # fmt: skip
@example(f_hz=80.0, n=400, amp=2.0, phase=0.0)  # refused before the check followed each line
def test_slow_act_oscillation_long_rois_flagged_and_both_mtfs(f_hz, n, amp, phase):
    """80-160 Hz on 400-800-line ROIs: 0.10-0.61 of the true blur with no flag before."""
    path = {"amp_px": [amp], "freq_hz": [f_hz], "phase_rad": [phase]}
    r, static = _pair(n, path)
    _check(r, static, n, path)
    osc = {"axis": "act", "amplitude_px": amp, "frequency_hz": f_hz, "phase_deg": float(np.degrees(phase))}
    terms = PushbroomTerms(SYSTEM.replace({"motion.oscillation": [osc]}))
    imaged = terms.as_imaged_otf(NU, "act", first_line=0, n_lines=n)[0] * static.mtf_at_nyquist
    assert abs(r.mtf_as_imaged_at_nyquist - imaged) < TOL


def test_straight_noisy_edge_no_flag_and_one_mtf():
    path = {"amp_px": [0.0], "freq_hz": [100.0], "phase_rad": [0.0]}
    img = render_tdi_edge(120, 60, angle_deg=ANGLE, x0=20.2, line_time_s=DT, stages=N, noise=0.006, seed=4, **path)
    r = measure_edge(img)
    assert "line_of_sight_motion" not in r.flags
    assert np.array_equal(r.mtf_aligned, r.mtf) and np.array_equal(r.mtf_as_imaged, r.mtf)
    assert r.los_motion_rms_px < 0.01
    d = json.loads(json.dumps(r.to_dict()))
    assert {"mtf_aligned", "mtf_as_imaged", "mtf_as_imaged_at_nyquist", "los_motion_rms_px"} <= set(d)


def test_run_comparison_like_with_like():
    """The run's edge check: the headline (each line located) against the budget's per-row terms, and the MTF as
    imaged against the prediction over the region's rows, in the check's details and its note."""
    from types import SimpleNamespace

    from affine import Affine

    from satchain.comparison.edge import edge_checks
    from satchain.prediction.core import EdgePrediction, Predictions
    from satchain.prediction.image_geometry import ImageGeometry

    cycles, n = 0.3, 100
    path = {"amp_px": [1.0], "freq_hz": [cycles / (N * DT)], "phase_rad": [np.pi / 2]}
    r, static = _pair(n, path)
    osc = {"axis": "act", "amplitude_px": 1.0, "frequency_hz": cycles / (N * DT), "phase_deg": 90.0}
    terms = PushbroomTerms(SYSTEM.replace({"motion.oscillation": [osc]}))
    per_row = abs(terms.per_row_otf(0.5, "act")[0]) * static.mtf_at_nyquist
    geo = ImageGeometry(Affine.identity(), (0.0, 0.0), np.sin(np.arange(n) / 9.0), np.zeros(n), {}, terms)
    edge = EdgePrediction("e1", (1.0, 0.0), per_row, lambda f: np.full(np.shape(f), per_row))
    pred = Predictions(mtf_along={}, edges={"e1": edge}, wedges={}, geometry=geo)
    entry = r.to_dict() | {"id": "e1", "roi_px": [0, 0, 50, n], "angle_deg_truth": ANGLE}
    details, rows = edge_checks([entry], pred, SimpleNamespace(edge_mtf_at_nyquist=0.03, edge_angle_deg=0.1))
    d = details[0].to_dict()
    assert abs(d["mtf_at_nyquist_error"]) < TOL and d["pass"]
    assert abs(d["mtf_as_imaged_at_nyquist_measured"] - d["mtf_as_imaged_at_nyquist_predicted"]) < TOL
    assert d["mtf_as_imaged_at_nyquist_predicted"] < per_row - 0.02  # the rows' displacements fold in
    assert "as imaged" in rows[0].note and d["los_motion_rms_px"] > 0.1


def test_cli_json_and_table_give_both_mtfs(tmp_path):
    from typer.testing import CliRunner

    from satchain.cli.measure import measure_app

    path = {"amp_px": [1.0], "freq_hz": [0.5 / (N * DT)], "phase_rad": [0.0]}
    img = render_tdi_edge(100, 50, angle_deg=ANGLE, x0=18.3, line_time_s=DT, stages=N, blur_px=0.35, **path)
    np.save(tmp_path / "wavy.npy", img)
    runner = CliRunner()
    d = json.loads(runner.invoke(measure_app, ["edge", str(tmp_path / "wavy.npy"), "--json"]).stdout)
    assert "line_of_sight_motion" in d["flags"] and d["los_motion_rms_px"] > 0.1
    assert len(d["mtf_as_imaged"]) == len(d["mtf_aligned"]) == len(d["mtf"])
    out = runner.invoke(measure_app, ["edge", str(tmp_path / "wavy.npy")]).stdout
    assert "as imaged" in out and "line_of_sight_motion" in out


def test_run_flags_an_alt_edge_whose_rows_move():
    """An ALT edge under an ALT oscillation (0.3 cycles a window): its lines (columns) cross many rows, so their
    positions stay straight and ``measure edge`` has nothing to flag; the run, which knows the rows'
    displacements, says its MTF row does not compare like with like (read 0.81 / 0.17 of the budget, unflagged)."""
    from types import SimpleNamespace

    from _render_tdi import render_tdi_alt_edge
    from affine import Affine

    from satchain.comparison.edge import edge_checks
    from satchain.prediction.core import EdgePrediction, Predictions
    from satchain.prediction.image_geometry import ImageGeometry

    kw = {"amp_px": [1.0], "freq_hz": [0.3 / (N * DT)], "phase_rad": [np.pi / 2], "line_time_s": DT, "stages": N}
    img, shift = render_tdi_alt_edge(60, 100, angle_deg=ANGLE, **kw)
    r = measure_edge(img)
    assert r.direction == "ALT" and "line_of_sight_motion" not in r.flags
    geo = ImageGeometry(Affine.identity(), (0.0, 0.0), np.zeros(60), shift, {}, None)
    edge = EdgePrediction("e2", (0.0, 1.0), 0.3, lambda f: np.full(np.shape(f), 0.3))
    pred = Predictions(mtf_along={}, edges={"e2": edge}, wedges={}, geometry=geo)
    entry = r.to_dict() | {"id": "e2", "roi_px": [0, 0, 100, 60], "angle_deg_truth": ANGLE}
    details, rows = edge_checks([entry], pred, SimpleNamespace(edge_mtf_at_nyquist=0.03, edge_angle_deg=0.1))
    assert "alt_line_of_sight_motion" in details[0].flags and "not like with like" in rows[0].note


@pytest.mark.parametrize(("f_hz", "n", "amp"), [(20.0, 800, 2.0), (40.0, 400, 1.0)])
def test_slow_oscillation_a_cycle_or_two_over_the_roi(f_hz, n, amp):
    """20 Hz over 800 lines (2 px: read 0.071 against 0.199, 'curved edge'), 40 Hz over 400 lines: the cubic
    follows part of the motion; the lines located follow all of it."""
    path = {"amp_px": [amp], "freq_hz": [f_hz], "phase_rad": [2.0]}
    r, static = _pair(n, path)
    _check(r, static, n, path)
    assert r.mtf_as_imaged_at_nyquist < r.mtf_aligned[100]  # the lines' displacements folded in blur further
