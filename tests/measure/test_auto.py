"""measure_auto on a small real pipeline: exact scene render -> Gaussian blur -> block average ("satellite").

The simulated image is ``block_mean_F(gaussian_filter(render, SIGMA))`` of a 0.1 m render, so its transfer
function is known in closed form: Gaussian ``exp(-2 pi^2 s^2 f^2)`` (s = SIGMA / F output px) x the output
pixel's box ``sinc(fx) sinc(fy)`` x the render pixel's box ``sinc(fx / F) sinc(fy / F)``.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter, gaussian_filter1d
from scipy.optimize import brentq

from satchain.errors import InputError
from satchain.measure.auto import measure_auto
from satchain.scene import BarTarget, Car, HyperbolicWedge, Scene, SiemensStar, SlantedEdge

P_SCENE = 0.1
F = 5
P = P_SCENE * F
SIGMA = 2.0  # render px
S_OUT = SIGMA / F  # output px
PERIODS_M = (3.0, 2.0, 1.5, 1.25, 1.0, 0.8)


def _scene() -> Scene:
    items = (
        SlantedEdge("edge_act", center_m=(15.0, 15.0), size_m=24.0, angle_deg=5.0, measures="act"),
        SlantedEdge("edge_alt", center_m=(15.0, 45.0), size_m=24.0, angle_deg=-7.0, measures="alt"),
        SiemensStar("star", center_m=(45.0, 15.0), radius_m=12.0, cycles=32),
        BarTarget("bars", origin_m=(32.0, 32.0), periods_m=PERIODS_M, gap_m=1.5),
        HyperbolicWedge("wedge", origin_m=(32.0, 45.0), length_m=30.0, line_width_end_m=0.2),
        Car("car", origin_m=(70.0, 10.0)),
    )
    return Scene(80.0, 60.0, items, background=0.2, pixel_m=P_SCENE)


def _simulate(render: np.ndarray, factor: int = F) -> np.ndarray:
    b = gaussian_filter(render.astype(float), SIGMA, mode="nearest")
    ny, nx = b.shape[0] // factor, b.shape[1] // factor
    return b[: ny * factor, : nx * factor].reshape(ny, factor, nx, factor).mean(axis=(1, 3))


def _mtf(fx, fy):
    """Closed-form system MTF (cy per output px)."""
    g = np.exp(-2 * np.pi**2 * S_OUT**2 * (fx**2 + fy**2))
    return g * np.sinc(fx) * np.sinc(fy) * np.sinc(fx / F) * np.sinc(fy / F)


@pytest.fixture(scope="module")
def pipeline():
    scene = _scene()
    render = scene.render()
    sim = _simulate(render)
    truth = scene.truth()
    return scene, render, sim, truth, measure_auto(sim, truth, pixel_m=P)


def test_every_item_is_measured_or_skipped_with_a_reason(pipeline):
    _, _, _, truth, res = pipeline
    d = res.to_dict()
    json.dumps(d, allow_nan=False)  # JSON-ready
    assert {"slanted_edges", "siemens_star", "bar_targets", "hyperbolic_wedge", "skipped"} <= set(d)
    measured = {e["id"] for k in ("slanted_edges", "siemens_star", "bar_targets", "hyperbolic_wedge") for e in d[k]}
    skipped = {s["id"]: s for s in d["skipped"]}
    assert measured == {"edge_act", "edge_alt", "star", "bars", "wedge"}
    assert {it["id"] for it in truth["items"]} <= measured | set(skipped)
    assert all(s["reason"] for s in d["skipped"])
    assert "no measurement defined" in skipped["car"]["reason"] and skipped["car"]["kind"] == "car"
    # 0.8 m period = 1.6 px: beyond Nyquist, skipped on its own; the five coarser groups are measured
    assert "Nyquist" in skipped["bars/group_5"]["reason"]
    assert len(d["bar_targets"][0]["groups"]) == 5
    e = d["slanted_edges"][0]
    keys = {"id", "angle_deg", "angle_deg_truth", "direction", "mtf_at_nyquist", "mtf50_cy_per_px", "rer"}
    assert keys | {"overshoot", "f_cy_per_px", "mtf"} <= set(e)
    assert {"orientation", "resolution_m", "threshold", "contrast"} <= set(d["hyperbolic_wedge"][0])
    assert d["calibration"]["fitted"] and d["calibration"]["gain"] == pytest.approx(1.0, abs=1e-6)


def test_edges_angle_direction_and_mtf(pipeline):
    _, _, _, _, res = pipeline
    for e in res.to_dict()["slanted_edges"]:
        assert e["angle_deg"] == pytest.approx(e["angle_deg_truth"], abs=0.2)
        assert e["direction"] == e["direction_truth"] == e["id"][-3:].upper()
        t = np.deg2rad(e["edge_angle_deg_image"])  # normal n = (cos t, -sin t) in image axes
        f = np.asarray(e["f_cy_per_px"])
        truth = _mtf(f * np.cos(t), f * np.sin(t))
        # 38 px ROI, no noise: MTF at Nyquist within 0.01, whole curve up to Nyquist within 0.008
        assert e["mtf_at_nyquist"] == pytest.approx(float(_mtf(0.5 * np.cos(t), 0.5 * np.sin(t))), abs=0.01)
        band = f <= 0.5
        assert np.max(np.abs(np.asarray(e["mtf"])[band] - truth[band])) < 0.008
        f50 = brentq(lambda v, t=t: _mtf(v * np.cos(t), v * np.sin(t)) - 0.5, 0.05, 0.9)
        assert e["mtf50_cy_per_px"] == pytest.approx(f50, abs=0.01)


def test_star_mtf_per_direction(pipeline):
    _, _, _, _, res = pipeline
    s = res.to_dict()["siemens_star"][0]
    assert s["cycles"] == 32 and s["input_modulation_from"] == "truth"
    assert s["input_modulation"] == pytest.approx(0.375 / 0.425)
    f = np.asarray(s["f_cy_per_px"])
    band = f <= 0.5
    truth = _mtf(f, 0 * f)  # ACT: frequency along x (ALT is the same for an isotropic system)
    for k in ("ACT", "ALT"):
        assert np.max(np.abs(np.asarray(s["mtf"][k], dtype=float)[band] - truth[band])) < 0.02, k
    assert s["mtf_at_nyquist"]["ACT"] == pytest.approx(float(_mtf(0.5, 0.0)), abs=0.02)


def _bars_1d(truth_item, group, background):
    """Exact 1-D model of a row through the bars: the same render/blur/block chain done along x only."""
    return _bars_1d_blurred(truth_item, group, background).reshape(-1, F).mean(axis=1)


def _bars_1d_blurred(truth_item, group, background):
    """The render/blur part of :func:`_bars_1d` (render grid)."""
    fine = 0.005  # every bar and plate edge lies on this grid (multiples of 1/8 m)
    x = np.arange(0.0, 80.0, fine) + fine / 2
    r = np.full(x.size, background)
    x0, _, x1, _ = group["bbox_m"]
    r[(x >= x0) & (x < x1)] = truth_item["dark"]
    for b in group["bars_m"]:
        r[(x >= b[0]) & (x < b[2])] = truth_item["bright"]
    render = r.reshape(-1, round(P_SCENE / fine)).mean(axis=1)
    return gaussian_filter1d(render, SIGMA, mode="nearest")


def test_bars_ctf_matches_an_independent_1d_model(pipeline):
    _, _, _, truth, res = pipeline
    item = next(it for it in truth["items"] if it["id"] == "bars")
    b = res.to_dict()["bar_targets"][0]
    assert b["direction"] == "ACT" and b["levels_from"] == "truth"
    c_large = (item["bright"] - item["dark"]) / (item["bright"] + item["dark"])
    for g in b["groups"]:
        group = item["groups"][g["group"]]
        assert g["period_px"] == pytest.approx(group["period_m"] / P)
        centres = [(bar[0] + bar[2]) / 2 for bar in group["bars_m"]]
        cols = np.arange(160)
        inside = cols[((cols + 0.5) * P >= centres[0]) & ((cols + 0.5) * P <= centres[-1])]
        assert g["roi_px"][0] == inside[0] and g["roi_px"][2] == inside[-1] + 1  # bar centre to bar centre
        # the continuous (pixel-integrated) profile at every 1/F px: pixel means of F render pixels at any offset
        fine = np.convolve(_bars_1d_blurred(item, group, truth["background"]), np.ones(F) / F, mode="valid")
        xs = (np.arange(fine.size) + F / 2) / F  # output-pixel coordinate of each window's centre
        span = fine[(xs * P >= centres[0] - 1e-9) & (xs * P <= centres[-1] + 1e-9)]
        expected = (span.max() - span.min()) / (span.max() + span.min()) / c_large
        if g["period_px"] < 2.5:  # the phase is not identifiable near 2 px: the sampled modulation, a lower bound
            assert g["ctf"] <= expected + 0.005 and any("lower bound" in f for f in g["flags"])
        else:  # a sharp system (sigma 0.4 px): the aliased harmonics come from the target's joint MTF
            assert g["ctf"] == pytest.approx(expected, abs=0.015), group["period_m"]
        # noise-free apart from the simulation's rounding: the joint model's own uncertainty only
        assert 0 <= g["ctf_std"] < 0.02
    assert np.all(np.asarray(b["mtf"]) <= np.asarray(b["ctf"]) + 1e-9)


def _ctf_square_wave(f):
    k = np.arange(1, 400, 2)
    return 4 / np.pi * np.sum((-1.0) ** ((k - 1) // 2) * _mtf(k * f, 0.0) / k)


def test_wedge_resolution_is_bounded_by_the_unsampled_contrast(pipeline):
    """Sampling picks values of the blurred profile, so the sampled contrast is at most the continuous one
    (target contrast x square-wave CTF): the 15 % point cannot lie beyond the continuous 15 % frequency."""
    _, _, _, truth, res = pipeline
    w = res.to_dict()["hyperbolic_wedge"][0]
    item = next(it for it in truth["items"] if it["id"] == "wedge")
    assert w["direction"] == "ALT" and w["threshold"] == 0.15
    c0 = (item["bright"] - item["dark"]) / (item["bright"] + item["dark"])
    f15 = brentq(lambda f: c0 * _ctf_square_wave(f) - 0.15, 0.2, 0.9)
    f_res = w["resolved_f_cy_per_px"]
    assert 0.35 < f_res <= f15 + 0.02
    assert w["resolution_m"] == pytest.approx(P * w["resolved_line_width_px"])
    assert w["resolved_f_cy_per_px"] == pytest.approx(1 / (2 * w["resolved_line_width_px"]))
    assert w["contrast"][0] > 0.6  # 2.5 px lines are well resolved
    lw, s = np.asarray(w["line_width_m"]), np.asarray(w["position_m_along_wedge"])
    np.testing.assert_allclose(lw, 1.25 * item["x0_m"] / (item["x0_m"] + s), rtol=1e-12)
    assert 0 < s[0] <= P and np.all(np.diff(s) == pytest.approx(P))


def test_radiometric_offset_and_gain_are_calibrated_out(pipeline):
    _, _, sim, truth, res = pipeline
    dn = 100.0 + 1000.0 * sim
    res2 = measure_auto(dn, truth, pixel_m=P)
    assert res2.calibration["offset"] == pytest.approx(100.0, abs=1e-3)
    assert res2.calibration["gain"] == pytest.approx(1000.0, rel=1e-6)
    a, b = res.to_dict(), res2.to_dict()
    np.testing.assert_allclose(a["siemens_star"][0]["mtf"]["ACT"], b["siemens_star"][0]["mtf"]["ACT"], atol=1e-6)
    np.testing.assert_allclose(a["bar_targets"][0]["ctf"], b["bar_targets"][0]["ctf"], atol=1e-6)
    np.testing.assert_allclose(a["hyperbolic_wedge"][0]["contrast"], b["hyperbolic_wedge"][0]["contrast"], atol=1e-6)
    np.testing.assert_allclose(a["slanted_edges"][0]["mtf"], b["slanted_edges"][0]["mtf"], atol=1e-6)


def test_origin_offset_shifts_every_region(pipeline):
    _, _, sim, truth, res = pipeline
    k = 3
    res2 = measure_auto(sim[k:, 2 * k :], truth, pixel_m=P, origin_m=(2 * k * P, k * P))
    a, b = res.to_dict(), res2.to_dict()
    for ea, eb in zip(a["slanted_edges"], b["slanted_edges"], strict=True):
        assert eb["roi_px"] == [
            ea["roi_px"][0] - 2 * k,
            ea["roi_px"][1] - k,
            ea["roi_px"][2] - 2 * k,
            ea["roi_px"][3] - k,
        ]
        np.testing.assert_allclose(ea["mtf"], eb["mtf"], atol=1e-9)
    np.testing.assert_allclose(a["bar_targets"][0]["ctf"], b["bar_targets"][0]["ctf"], atol=1e-9)
    assert a["hyperbolic_wedge"][0]["resolution_m"] == pytest.approx(b["hyperbolic_wedge"][0]["resolution_m"])


def _transpose_truth(truth: dict) -> dict:
    """The truth of the transposed scene (x <-> y): act <-> alt, horizontal <-> vertical."""
    t = copy.deepcopy(truth)
    swap = {"act": "alt", "alt": "act", "horizontal": "vertical", "vertical": "horizontal"}
    for it in t["items"]:
        x0, y0, x1, y1 = it["bbox_m"]
        it["bbox_m"] = [y0, x0, y1, x1]
        for key in ("edge_point_m", "edge_direction", "normal_to_bright", "center_m", "local_origin_m"):
            if key in it:
                it[key] = it[key][::-1]
        for key in ("measures", "orientation"):
            if key in it:
                it[key] = swap[it[key]]
        for g in it.get("groups", []):
            g["bbox_m"] = [g["bbox_m"][i] for i in (1, 0, 3, 2)]
            g["bars_m"] = [[bar[i] for i in (1, 0, 3, 2)] for bar in g["bars_m"]]
    return t


def test_transposed_image_swaps_act_and_alt(pipeline):
    _, _, sim, truth, res = pipeline
    res_t = measure_auto(sim.T, _transpose_truth(truth), pixel_m=P)
    a, b = res.to_dict(), res_t.to_dict()
    for ea, eb in zip(a["slanted_edges"], b["slanted_edges"], strict=True):
        assert {ea["direction"], eb["direction"]} == {"ACT", "ALT"}
        assert eb["angle_deg"] == pytest.approx(ea["angle_deg"], abs=1e-6)
        np.testing.assert_allclose(ea["mtf"], eb["mtf"], atol=1e-9)
    sa, sb = a["siemens_star"][0]["mtf"], b["siemens_star"][0]["mtf"]
    np.testing.assert_allclose(sa["ACT"], sb["ALT"], atol=1e-9)
    np.testing.assert_allclose(sa["D45"], sb["D45"], atol=1e-9)
    assert b["bar_targets"][0]["direction"] == "ALT"
    np.testing.assert_allclose(a["bar_targets"][0]["ctf"], b["bar_targets"][0]["ctf"], atol=1e-12)
    assert b["hyperbolic_wedge"][0]["direction"] == "ACT"
    np.testing.assert_allclose(a["hyperbolic_wedge"][0]["contrast"], b["hyperbolic_wedge"][0]["contrast"], atol=1e-12)


def test_too_coarse_pixels_skip_everything_with_reasons(pipeline):
    _, render, _, truth, _ = pipeline
    coarse = _simulate(render, factor=25)  # 2.5 m pixels
    d = measure_auto(coarse, truth, pixel_m=2.5).to_dict()
    assert not any(d[k] for k in ("slanted_edges", "siemens_star", "bar_targets", "hyperbolic_wedge"))
    reasons = {s["id"]: s["reason"] for s in d["skipped"]}
    assert {"edge_act", "edge_alt", "star", "bars", "wedge", "car"} <= set(reasons)
    for k in ("edge_act", "edge_alt", "star", "wedge"):
        assert "too small" in reasons[k], reasons[k]
    assert "no bar group is measurable" in reasons["bars"]


def test_pixel_size_resolution_and_bad_truth(pipeline):
    scene, _, sim, truth, _ = pipeline
    with pytest.raises(InputError, match="pixel_m"):
        measure_auto(sim, truth)
    t2 = dict(truth, image_pixel_m=P)
    assert measure_auto(sim, t2, ids=["edge_act"]).pixel_m == P
    small = scene.render((0, 0, 300, 300))  # the render itself (left part): shape differs from the window
    with pytest.raises(InputError, match="pixel_m"):
        measure_auto(small, truth)
    with pytest.raises(InputError, match="truth"):
        measure_auto(sim, {"items": "nope"}, pixel_m=P)
    with pytest.raises(InputError, match="no such item"):
        measure_auto(sim, truth, pixel_m=P, ids=["missing"])
    nan = sim.copy()
    nan[30, 30] = np.nan  # inside edge_act's region: that item fails with the reason, the rest is measured
    d = measure_auto(nan, truth, pixel_m=P).to_dict()
    reason = {s["id"]: s["reason"] for s in d["skipped"]}["edge_act"]
    assert "NaN" in reason and {e["id"] for e in d["slanted_edges"]} == {"edge_alt"}
