"""Line-by-line edge positions and the line-of-sight motion fitted to them (issue 20, point 4).

Every image is rendered here by :mod:`_render_jitter` (an exact pixel-area integral of a Gaussian-blurred
step whose position per line is ``x0 + y tan(theta) + sum A sin(2 pi f t_y + phi)``), independent of satchain.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from _render_jitter import render_wobbly_edge
from hypothesis import example, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.config.system import load_preset
from satchain.errors import ConfigError, InputError
from satchain.measure import measure_edge
from satchain.measure._jitter_fit import frequency_grid
from satchain.measure.jitter import _find_peaks, measure_jitter

DT = 1e-3  # line time of the hypothesis cases (s): Nyquist 500 Hz


def _render(n, angle, *, amp=(), freq=(), phase=(), noise=0.0, blur=0.7, dt=DT, seed=0, x0=15.3, margin=15):
    width = int(np.ceil(x0 + n * np.tan(np.radians(angle)) + max([0.0, *amp]) + margin))
    return render_wobbly_edge(
        n, width, angle_deg=angle, x0=x0, amp_px=amp, freq_hz=freq, phase_rad=phase, line_time_s=dt,
        blur_px=blur, noise=noise, seed=seed,
    )  # fmt: skip


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


# ------------------------------------------------------------------------------------------ per-line positions


@settings(max_examples=12, deadline=None)
@given(
    angle=st.floats(1.0, 8.0),
    amp=st.floats(0.2, 3.0),
    cycles_per_line=st.floats(0.002, 0.45),
    phase=st.floats(0.0, 2 * np.pi),
    blur=st.floats(0.5, 1.2),
)
@example(angle=1.0, amp=1.0, cycles_per_line=1 / 3, phase=0.5, blur=1.0)  # three tracks of phases
@example(angle=1.0, amp=1.0, cycles_per_line=0.421875, phase=0.0, blur=1.0)
def test_noise_free_positions_equal_the_renderers_truth(angle, amp, cycles_per_line, phase, blur):
    img, truth = _render(300, angle, amp=[amp], freq=[cycles_per_line / DT], phase=[phase], blur=blur)
    r = measure_jitter(img, line_time_s=DT)
    ok = np.isfinite(r.edge_position_px)
    assert np.count_nonzero(ok) >= 290
    assert np.max(np.abs(r.edge_position_px[ok] - truth[ok])) < 2e-3
    assert np.array_equal(r.lines, np.arange(300))


@pytest.mark.parametrize(("angle", "noise", "blur"), [(2.5, 0.01, 0.6), (6.0, 0.02, 0.9), (4.0, 0.005, 0.5)])
def test_noisy_positions_are_unbiased_with_their_stated_sigma(angle, noise, blur):
    errs, sigs = [], []
    for seed in range(3):
        img, truth = _render(600, angle, amp=[1.2], freq=[37.0], phase=[1.0], noise=noise, blur=blur, seed=seed)
        r = measure_jitter(img, line_time_s=DT)
        errs.append(r.edge_position_px - truth)
        sigs.append(r.edge_position_sigma_px)
    e, s = np.concatenate(errs), np.concatenate(sigs)
    ok = np.isfinite(e)
    sig = float(np.median(s[ok]))
    assert abs(np.mean(e[ok])) < 0.2 * sig + 4 * sig / np.sqrt(ok.sum())
    assert 0.85 < np.std(e[ok]) / sig < 1.2


def test_measure_edge_reports_the_lines_with_the_roi_offset_and_null_where_masked():
    img, truth = _render(200, 4.0, amp=[0.4], freq=[30.0], phase=[0.2], noise=0.003)
    img = np.pad(img, ((7, 3), (11, 5)), mode="edge")
    valid = np.ones(img.shape, dtype=bool)
    valid[7 + 50 : 7 + 53, :] = False  # three lines masked out
    roi = (9, 5, img.shape[1] - 2, img.shape[0] - 1)
    r = measure_edge(img, roi=roi, valid=valid)
    assert r.lines[0] == 5 and r.lines[-1] == img.shape[0] - 2 and r.direction == "ACT"
    pos = dict(zip(r.lines.tolist(), r.edge_position_px.tolist(), strict=True))
    assert all(np.isnan(pos[7 + k]) for k in (50, 51, 52))
    y = np.array([k for k in range(10, 190) if k not in (50, 51, 52)])
    got = np.array([pos[7 + k] for k in y]) - 11  # image x back to the render's x
    assert np.max(np.abs(got - truth[y])) < 0.05
    d = r.to_dict()
    assert d["edge_position_px"][r.lines.tolist().index(57)] is None and len(d["lines"]) == len(r.lines)
    j = measure_jitter(img, roi=roi, valid=valid, line_time_s=DT)
    np.testing.assert_allclose(j.edge_position_px, r.edge_position_px, atol=1e-9, equal_nan=True)


def test_an_alt_edge_gives_y_positions_per_column_and_measure_jitter_refuses_it():
    img, truth = _render(160, 5.0, noise=0.002)
    r = measure_edge(img.T)
    assert r.direction == "ALT" and np.array_equal(r.lines, np.arange(160))
    ok = np.isfinite(r.edge_position_px)
    assert ok.sum() > 140 and np.max(np.abs(r.edge_position_px[ok] - truth[ok])) < 0.03
    with pytest.raises(InputError, match="near-horizontal"):
        measure_jitter(img.T, line_time_s=DT)


# ------------------------------------------------------------------------------------------------- sinusoids


def test_issue_acceptance_2px_at_20hz_over_800_lines_with_a_3_deg_edge():
    dt = load_preset("ankarasat3").line_time_s
    for noise in (0.0, 0.01):
        img, _ = _render(800, 3.0, amp=[2.0], freq=[20.0], phase=[0.7], noise=noise, blur=0.6, dt=dt)
        p = measure_jitter(img, line_time_s=dt).peaks[0]
        assert abs(p.amplitude_px - 2.0) < 0.05
        assert abs(p.amplitude_px - 2.0) < 4 * p.amplitude_sigma_px + 1e-3
        assert abs(p.frequency_hz - 20.0) < 4 * p.frequency_sigma_hz + 1e-3
        assert p.cycles == pytest.approx(p.frequency_hz * 800 * dt) and "few_cycles" in p.flags


@settings(max_examples=14, deadline=None)
@given(
    angle=st.floats(1.0, 8.0),
    amp=st.floats(0.2, 3.0),
    cycles_per_line=st.floats(0.01, 0.45),
    phase=st.floats(-np.pi, np.pi),
    noise=st.floats(0.0, 0.02),
    seed=st.integers(0, 2**16),
)
@example(angle=1.0, amp=3.0, cycles_per_line=0.125, phase=0.0, noise=0.0, seed=0)  # a zigzag: more y than x steps
def test_amplitude_frequency_and_phase_within_their_stated_sigma(angle, amp, cycles_per_line, phase, noise, seed):
    f = cycles_per_line / DT
    img, _ = _render(400, angle, amp=[amp], freq=[f], phase=[phase], noise=noise, seed=seed)
    r = measure_jitter(img, line_time_s=DT, max_peaks=2)
    p = r.peaks[0]
    assert abs(p.amplitude_px - amp) < 4 * p.amplitude_sigma_px + 2e-3
    assert abs(p.frequency_hz - f) < 4 * p.frequency_sigma_hz + 1e-3
    assert abs(_wrap(np.radians(p.phase_deg) - phase)) < 4 * np.radians(p.phase_sigma_deg) + 2e-3
    assert p.aliases_hz == pytest.approx((1 / DT - p.frequency_hz, 1 / DT + p.frequency_hz))
    assert all(q.amplitude_px < 0.05 * amp + 4 * q.amplitude_sigma_px + 0.01 for q in r.peaks[1:])


def test_two_sinusoids_and_missing_lines():
    img, _ = _render(700, 2.0, amp=[0.8, 0.15], freq=[23.0, 171.0], phase=[0.3, -1.1], noise=0.004)
    valid = np.ones(img.shape, dtype=bool)
    valid[100:140] = False
    valid[400:403] = False
    r = measure_jitter(img, line_time_s=DT, valid=valid)
    assert r.n_lines_used == 700 - 43 and np.isnan(r.edge_position_px[100:140]).all()
    got = sorted((p.frequency_hz, p.amplitude_px) for p in r.peaks)
    assert len(got) == 2
    for (f, a), (f0, a0) in zip(got, [(23.0, 0.8), (171.0, 0.15)], strict=True):
        assert f == pytest.approx(f0, abs=0.05) and a == pytest.approx(a0, abs=0.01)


def test_a_motion_above_the_line_rate_nyquist_is_reported_folded_with_its_alias():
    f_true = 1.0 / DT - 130.0  # 870 Hz at a 1 kHz line rate
    img, _ = _render(500, 3.0, amp=[0.5], freq=[f_true], phase=[0.4], noise=0.003)
    r = measure_jitter(img, line_time_s=DT)
    p = r.peaks[0]
    assert p.frequency_hz == pytest.approx(130.0, abs=0.05) and p.amplitude_px == pytest.approx(0.5, abs=0.01)
    assert p.aliases_hz[0] == pytest.approx(f_true, abs=0.05)
    # 130 Hz is far from the Nyquist fold: nothing in the lines tells it from a 130 Hz motion (aliases_hz lists
    # 870 Hz), so no flag says it is folded (issue 29: the flag was set on every result, even at 5 Hz)
    assert "aliasing" not in r.flags and r.nyquist_hz == pytest.approx(500.0)


# ----------------------------------------------------------------------------------------------- no false peak


@pytest.mark.parametrize(("angle", "noise", "seed"), [(1.5, 0.01, 1), (3.0, 0.02, 2), (5.5, 0.005, 3), (7.5, 0.0, 4)])
def test_a_straight_edge_shows_no_peak(angle, noise, seed):
    img, _ = _render(500, angle, noise=noise, seed=seed, blur=0.6)
    r = measure_jitter(img, line_time_s=DT)
    assert r.peaks == () and "no_peak" in r.flags
    # noise alone: rms^2 - sigma^2 fluctuates by ~2 sqrt(2 / N) sigma^2 (2 sigma)
    assert r.rms_motion_px < np.sqrt(2 * np.sqrt(2 / 500)) * r.position_noise_px + 1e-3
    if noise > 0:
        assert 0.8 < r.residual_rms_px / r.position_noise_px < 1.2


def test_false_alarm_rate_on_white_noise_is_at_most_the_stated_probability():
    """Pure white noise about a tilted line: the fraction of records with a reported peak <= false_alarm
    (Baluev's bound; binomial 3-sigma margin)."""
    rng = np.random.default_rng(20)
    lines = np.arange(160, dtype=float)
    t = lines * DT
    freqs = frequency_grid(t, DT)
    alpha, trials = 0.05, 120
    hits = 0
    for _ in range(trials):
        y = 3.0 + 0.06 * lines + rng.normal(0.0, 0.03, lines.size)
        hits += _find_peaks(t, y, lines, freqs, (1, alpha, 0.0))[0] is not None
    assert hits / trials <= alpha + 3 * np.sqrt(alpha * (1 - alpha) / trials)


# --------------------------------------------------------------------------------------------- bad input, CLI


def test_no_edge_is_refused():
    noise = np.random.default_rng(3).normal(0.5, 0.01, (200, 40))
    with pytest.raises(InputError, match="no edge"):
        measure_jitter(noise, line_time_s=DT)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"line_time_s": 0.0}, "line_time_s"),
        ({"line_time_s": float("nan")}, "line_time_s"),
        ({"line_time_s": DT, "max_peaks": 0}, "max_peaks"),
        ({"line_time_s": DT, "max_peaks": 2.5}, "max_peaks"),
        ({"line_time_s": DT, "false_alarm": 0.7}, "false_alarm"),
        ({"line_time_s": DT, "min_amplitude_px": -1}, "min_amplitude_px"),
    ],
)
def test_bad_options_name_the_parameter(kwargs, match):
    img, _ = _render(60, 4.0)
    with pytest.raises(ConfigError, match=match):
        measure_jitter(img, **kwargs)


def test_cli_json_table_and_outputs(tmp_path):
    img, _ = _render(400, 3.0, amp=[1.0], freq=[40.0], phase=[0.0], noise=0.004)
    path = tmp_path / "edge.npy"
    np.save(path, img)
    run = CliRunner().invoke(app, ["measure", "jitter", str(path), "--line-time", "1e-3", "--json"])
    assert run.exit_code == 0, run.output
    d = json.loads(run.stdout)
    assert d["peaks"][0]["amplitude_px"] == pytest.approx(1.0, abs=0.01) and len(d["edge_position_px"]) == 400
    run = CliRunner().invoke(app, ["measure", "jitter", str(path), "--line-time", "1e-3", "-o", str(tmp_path / "o")])
    assert run.exit_code == 0 and "significant sinusoids" in run.stdout
    assert (tmp_path / "o" / "jitter.json").is_file() and (tmp_path / "o" / "jitter.png").stat().st_size > 10_000
    run = CliRunner().invoke(app, ["measure", "jitter", str(path), "--line-time", "-2"])
    assert run.exit_code == 2 and run.stderr.strip().startswith("error: --line-time = -2")
    run = CliRunner().invoke(app, ["measure", "edge", str(path), "--json"])
    e = json.loads(run.stdout)
    assert len(e["lines"]) == len(e["edge_position_px"]) == len(e["edge_position_sigma_px"]) == 400


def test_aliasing_flag_only_near_or_above_the_line_rate_nyquist():
    """5 Hz: a clean, well-resolved slow motion, no ``aliasing``; a motion 0.3 / record above Nyquist folds to
    within the resolution below it: flagged (issue 29, item 11)."""
    n = 500
    img, _ = _render(n, 3.0, amp=[0.5], freq=[5.0], phase=[0.4], noise=0.003)
    r = measure_jitter(img, line_time_s=DT)
    assert r.peaks[0].frequency_hz == pytest.approx(5.0, abs=0.05) and "aliasing" not in r.flags
    f_true = 0.5 / DT + 0.3 / (n * DT)  # 500.6 Hz at a 1 kHz line rate: appears at 499.4 Hz
    img, _ = _render(n, 3.0, amp=[0.5], freq=[f_true], phase=[0.4], noise=0.003)
    r = measure_jitter(img, line_time_s=DT)
    assert r.peaks[0].frequency_hz == pytest.approx(1.0 / DT - f_true, abs=0.2) and "aliasing" in r.flags
