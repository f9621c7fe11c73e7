"""Known answers for the comparison core: predictions from closed-form 2-D MTFs, measurements made up so the
expected error of every check is known exactly, and the tolerance boundary itself."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain import units
from satchain.comparison import BAR_COMPARE_MAX_CY_PER_PX, compare
from satchain.config.run import Tolerances
from satchain.prediction.core import (
    DIRECTIONS,
    AxisMTF,
    WedgePrediction,
    predict,
    predict_from_mtf,
    saturation_warnings,
)
from satchain.prediction.quality import giqe5, giqe5_rer
from satchain.tf.ctf import band_limited, wedge_resolution_m

TOL = Tolerances()
A, B = 1.0, 2.0  # the Gaussian MTF falls twice as fast along y (ALT) as along x (ACT)


def gauss(fx, fy):
    return np.exp(-((A * fx) ** 2) - (B * fy) ** 2)


def gauss_along(f, ux, uy):
    return np.exp(-(f**2) * ((A * ux) ** 2 + (B * uy) ** 2))


def edge_truth(eid, angle_deg):
    t = math.radians(angle_deg)
    return {"kind": "slanted_edge", "id": eid, "normal_to_bright": [math.cos(t), math.sin(t)]}


def edge_meas(eid, direction, mtf_nyq, **kw):
    return {
        "id": eid,
        "direction": direction,
        "mtf_at_nyquist": mtf_nyq,
        "f_cy_per_px": [0.25, 0.5],
        "mtf": [1, 1],
    } | kw


def rows_of(comp, kind):
    return [r for r in comp.rows if r.kind == kind]


# ---------------------------------------------------------------------------------------------- edges


def test_edge_prediction_is_the_mtf_at_half_a_cycle_per_pixel_along_the_truth_normal():
    truth = {"items": [edge_truth("e_act", 8.0), edge_truth("e_alt", 90.0 - 7.0)]}
    p = predict_from_mtf(gauss, truth, gsd_m=1.0)
    for eid, deg in (("e_act", 8.0), ("e_alt", 83.0)):
        u = (math.cos(math.radians(deg)), math.sin(math.radians(deg)))
        assert p.edges[eid].mtf_at_nyquist == pytest.approx(gauss_along(0.5, *u), rel=1e-12)
        assert p.edges[eid].normal == pytest.approx(u, abs=1e-15)
    # the two directions differ a lot, so a swapped axis or a wrong frequency cannot pass
    assert p.edges["e_alt"].mtf_at_nyquist < 0.45 < 0.75 < p.edges["e_act"].mtf_at_nyquist


def test_edge_check_error_sign_curve_and_pass():
    truth = {"items": [edge_truth("e", 8.0)]}
    p = predict_from_mtf(gauss, truth, gsd_m=1.0)
    u = (math.cos(math.radians(8.0)), math.sin(math.radians(8.0)))
    exact = gauss_along(0.5, *u)
    m = {"slanted_edges": [edge_meas("e", "ACT", exact - 0.015, angle_deg=8.1, angle_deg_truth=8.0)]}
    c = compare(m, p, TOL)
    (mtf_row,) = rows_of(c, "edge_mtf_at_nyquist")
    assert mtf_row.error == pytest.approx(-0.015, abs=1e-12) and mtf_row.passed is True
    assert c.slanted_edges[0].mtf_predicted == pytest.approx(gauss_along(np.array([0.25, 0.5]), *u), rel=1e-12)
    (angle_row,) = rows_of(c, "edge_angle")
    assert angle_row.error == pytest.approx(0.1, abs=1e-12) and angle_row.passed is True
    m = {"slanted_edges": [edge_meas("e", "ACT", exact - 0.03, angle_deg=8.3, angle_deg_truth=8.0)]}
    c = compare(m, p, TOL)
    assert [r.passed for r in c.rows if r.kind.startswith("edge")] == [False, False]
    assert c.passed is False and c.n_failed == 2


def test_edge_without_truth_uses_its_measured_axis():
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    c = compare({"slanted_edges": [edge_meas("x", "ALT", math.exp(-1.0))]}, p, TOL)
    assert c.slanted_edges[0].mtf_at_nyquist_predicted == pytest.approx(math.exp(-(B**2) * 0.25), rel=1e-12)
    assert rows_of(c, "edge_mtf_at_nyquist")[0].passed is True


def test_skipped_targets_are_na_rows_with_their_reason_and_objects_are_not_checks():
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    skipped = [
        {"id": "e", "kind": "slanted_edge", "reason": "clipped at the full well"},
        {"id": "w", "kind": "hyperbolic_wedge", "reason": "outside the image"},
        {"id": "car_1", "kind": "car", "reason": "no measurement defined"},
    ]
    c = compare({"skipped": skipped}, p, TOL)
    na = [r for r in c.rows if r.kind != "niirs"]
    assert [(r.id, r.kind, r.passed) for r in na] == [
        ("e", "edge_mtf_at_nyquist", None),
        ("w", "wedge_resolution", None),
    ]
    assert "clipped at the full well" in na[0].reason and na[1].tolerance == TOL.wedge_resolution_rel
    assert c.passed is None and c.n_failed == 0


def test_comparison_prints_as_a_table_with_every_verdict():
    p = predict_from_mtf(gauss, {"items": [edge_truth("e", 8.0)]}, gsd_m=1.0)
    m = {"slanted_edges": [edge_meas("e", "ACT", 0.9, angle_deg=8.0, angle_deg_truth=8.0)]}
    lines = str(compare(m, p, TOL)).splitlines()
    head = ["figure", "of", "merit", "measured", "predicted", "error", "sigma", "z", "tolerance", "result"]
    assert lines[0].split() == head
    assert lines[1].endswith("FAIL") and "0.9" in lines[1] and lines[2].endswith("pass") and lines[3].endswith("n/a")


def test_edge_without_mtf_is_not_applicable_not_a_failure():
    p = predict_from_mtf(gauss, {"items": [edge_truth("e", 8.0)]}, gsd_m=1.0)
    c = compare({"slanted_edges": [edge_meas("e", "ACT", None)]}, p, TOL)
    row = rows_of(c, "edge_mtf_at_nyquist")[0]
    assert row.passed is None and row.measured is None and "no MTF" in row.reason
    assert c.passed is None and c.n_checked == 0 and c.n_failed == 0


# ---------------------------------------------------------------------------------------------- tolerance


@pytest.mark.parametrize(
    ("measured", "expected"),
    [(0.625, True), (0.375, True), (0.625 + 2**-40, False), (0.375 - 2**-40, False), (0.25, False), (0.75, False)],
)
def test_tolerance_is_inclusive_and_two_sided(measured, expected):
    def half(fx, fy):
        return np.full(np.broadcast(fx, fy).shape, 0.5)

    p = predict_from_mtf(half, {"items": [edge_truth("e", 5.0)]}, gsd_m=1.0)
    tol = Tolerances(edge_mtf_at_nyquist=0.125)
    row = rows_of(compare({"slanted_edges": [edge_meas("e", "ACT", measured)]}, p, tol), "edge_mtf_at_nyquist")[0]
    assert row.passed is expected


# ---------------------------------------------------------------------------------------------- star


def star_meas(offsets=None, f=(0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6)):
    f = np.asarray(f)
    dirs = {"ACT": (1, 0), "ALT": (0, 1), "D45": (0.5**0.5, 0.5**0.5), "D135": (0.5**0.5, -(0.5**0.5))}
    mtf = {d: (gauss_along(f, *u) + (offsets or {}).get(d, 0.0)).tolist() for d, u in dirs.items()}
    return {"siemens_star": [{"id": "s", "f_cy_per_px": f.tolist(), "mtf": mtf}]}


def test_star_exact_measurement_has_zero_error_per_direction():
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    c = compare(star_meas(), p, TOL)
    (row,) = rows_of(c, "star_mtf")
    assert row.error == pytest.approx(0.0, abs=1e-12) and row.passed is True
    assert row.measured == pytest.approx(row.predicted, abs=1e-12) == row.model_prediction  # no star prediction
    for d, v in c.siemens_star[0].directions.items():
        assert v["max_abs_error_to_nyquist"] == pytest.approx(0.0, abs=1e-12), d


@pytest.mark.parametrize("d", ["ACT", "ALT", "D45", "D135"])
def test_star_error_is_the_largest_absolute_difference_in_any_direction(d):
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    c = compare(star_meas({d: -0.04}), p, TOL)  # below the prediction: the error is -0.04, |-0.04| checked
    (row,) = rows_of(c, "star_mtf")
    assert row.error == pytest.approx(-0.04, abs=1e-12) and row.passed is True
    assert row.measured - row.predicted == pytest.approx(-0.04, abs=1e-12)
    assert c.siemens_star[0].worst_direction == d and c.siemens_star[0].max_abs_error_to_nyquist == pytest.approx(0.04)
    c = compare(star_meas({d: -0.07}), p, TOL)
    assert rows_of(c, "star_mtf")[0].error == pytest.approx(-0.07, abs=1e-12)
    assert c.passed is False


def test_star_beyond_nyquist_and_below_005_is_not_compared_and_empty_is_na():
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    m = star_meas()
    m["siemens_star"][0]["mtf"]["ACT"][-1] += 0.5  # at 0.6 cy/px: beyond Nyquist
    assert rows_of(compare(m, p, TOL), "star_mtf")[0].passed is True
    m = star_meas(f=(0.02, 0.6, 0.7))
    row = rows_of(compare(m, p, TOL), "star_mtf")[0]
    assert row.passed is None and row.measured is None and row.reason


# ---------------------------------------------------------------------------------------------- bars


def coltman_gauss(f, b):
    k = np.arange(200)[:, None]
    return (4 / np.pi) * np.sum((-1.0) ** k * np.exp(-((b * (2 * k + 1) * f) ** 2)) / (2 * k + 1), axis=0)


@pytest.mark.parametrize(("direction", "b"), [("ACT", A), ("ALT", B)])
def test_bars_compare_with_coltman_along_the_modulation_axis(direction, b):
    f = np.array([0.05, 0.1, 0.2, 0.3, BAR_COMPARE_MAX_CY_PER_PX + 0.05])
    ctf = coltman_gauss(f, b)
    ctf[1] -= 0.05  # a known error, inside the compared range
    ctf[-1] += 0.5  # finer than 2.5 px per period: listed, not compared
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    m = {"bar_targets": [{"id": "b", "direction": direction, "f_cy_per_px": f.tolist(), "ctf": ctf.tolist()}]}
    c = compare(m, p, TOL)
    (row,) = rows_of(c, "bar_ctf")
    assert row.measured == pytest.approx(0.05, abs=1e-9) and row.passed is True
    assert c.bar_targets[0].ctf_coltman_predicted == pytest.approx(coltman_gauss(f, b), abs=1e-12)


def test_bars_only_fine_groups_is_na():
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    f = [BAR_COMPARE_MAX_CY_PER_PX + 0.02, BAR_COMPARE_MAX_CY_PER_PX + 0.05]
    m = {"bar_targets": [{"id": "b", "direction": "ACT", "f_cy_per_px": f, "ctf": [0.0, 0.0]}]}
    row = rows_of(compare(m, p, TOL), "bar_ctf")[0]
    assert row.passed is None and f"{1 / BAR_COMPARE_MAX_CY_PER_PX:g} px per period" in row.reason


# ---------------------------------------------------------------------------------------------- wedge


def triangle(fx, fy):  # cutoff 1 cy/px along x (ACT), 0.4 cy/px along y (ALT)
    return np.clip(1.0 - np.hypot(fx / 1.0, fy / 0.4), 0.0, None)


def wedge_closed_form(cutoff, gsd, thr, limit):  # (4/pi)(1 - f/fc) = thr above fc / 3
    f = cutoff * (1.0 - math.pi * thr / 4.0)
    assert f > cutoff / 3
    return max(gsd / (2 * f), limit)


def test_coltman_wedge_resolution_closed_form_per_axis_including_the_sampling_limit():
    """ctf.wedge_resolution_m (Coltman's CTF of an infinite square wave, clamped to the sampling limit); a run's
    wedge prediction no longer uses it (tests/test_wedge_prediction.py)."""
    gsd, thr = 0.5, 0.15
    along = {d: AxisMTF(triangle, u) for d, u in DIRECTIONS.items()}
    alt = wedge_resolution_m(along["ALT"], gsd_m=gsd, threshold=thr)
    assert alt == pytest.approx(wedge_closed_form(0.4, gsd, thr, gsd), rel=1e-7) and alt > 1.4 * gsd
    assert wedge_resolution_m(along["ACT"], gsd_m=gsd, threshold=thr) == gsd  # 0.567 GSD, limited by sampling
    c_diag = 1.0 / math.sqrt(0.5 * (1.0 + 1.0 / 0.4**2))
    diag = wedge_resolution_m(along["D135"], gsd_m=gsd, threshold=thr, sampling_limit_m=gsd / math.sqrt(2))
    assert diag == pytest.approx(wedge_closed_form(c_diag, gsd, thr, gsd / math.sqrt(2)), rel=1e-7)


def test_coltman_wedge_resolution_of_a_perfect_system_is_the_sampling_limit_and_hopeless_is_nan():
    one = band_limited(lambda f: np.ones_like(f), cutoff=100.0)
    assert wedge_resolution_m(one, gsd_m=2.0, threshold=0.15) == 2.0
    tiny = band_limited(lambda f: 0.01 * (1.0 - f / 5.0), cutoff=5.0)
    assert math.isnan(wedge_resolution_m(tiny, gsd_m=2.0, threshold=0.15))


@pytest.mark.parametrize(("orientation", "axis"), [("horizontal", "ALT"), ("vertical", "ACT"), ("diagonal", "D135")])
def test_wedge_check_relative_error_on_the_right_axis(orientation, axis):
    p0 = predict_from_mtf(triangle, {"items": []}, gsd_m=0.5)
    p = dataclasses.replace(p0, wedges={"w": WedgePrediction("w", axis, 0.6, 0.5)})
    pred = p.wedges["w"].resolution_m
    for factor, ok in ((1.1, True), (0.9, True), (1.2, False), (0.8, False)):
        m = {"hyperbolic_wedge": [{"id": "w", "orientation": orientation, "resolution_m": pred * factor}]}
        (row,) = rows_of(compare(m, p, TOL), "wedge_resolution")
        assert row.error == pytest.approx(factor - 1, abs=1e-12) and row.passed is ok
        assert axis in row.figure
    m = {"hyperbolic_wedge": [{"id": "w", "orientation": orientation, "resolution_m": None}]}
    assert rows_of(compare(m, p, TOL), "wedge_resolution")[0].passed is None
    m["hyperbolic_wedge"][0]["resolution_m"] = 1.0  # a wedge the prediction was not asked for: n/a, said why
    row = rows_of(compare(m, p0, TOL), "wedge_resolution")[0]
    assert row.passed is None and "no prediction" in row.reason


# ---------------------------------------------------------------------------------------------- NIIRS


def test_niirs_from_measured_rer_and_snr():
    q = {"giqe5": 4.0, "rer_giqe5": 0.5, "snr": 40.0}
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=0.5, quality=q, gsd_los_m=0.55, elevation_deg=70.0)
    edges = [
        edge_meas("a1", "ACT", 0.3, rer=0.60),
        edge_meas("a2", "ACT", 0.3, rer=0.64),
        edge_meas("l1", "ALT", 0.3, rer=0.45),
    ]
    m = {"slanted_edges": edges, "snr": {"snr": 35.0}}
    c = compare(m, p, TOL)
    expected = giqe5(gsd_in=0.55 / 0.0254, rer=giqe5_rer(0.62, 0.45), snr=35.0, elevation_deg=70.0)
    assert units.m_to_inches(0.0254) == pytest.approx(1.0)
    (row,) = rows_of(c, "niirs")
    assert row.measured == pytest.approx(expected, rel=1e-12) and row.predicted == 4.0
    assert row.error == pytest.approx(expected - 4.0, rel=1e-12)
    assert row.passed is (abs(expected - 4.0) <= TOL.niirs)
    assert c.niirs.rer_measured == pytest.approx(giqe5_rer(0.62, 0.45))


def test_niirs_without_snr_or_without_an_alt_edge_is_na():
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=0.5, quality={"giqe5": 4.0, "rer_giqe5": 0.5, "snr": 40.0})
    c = compare({"slanted_edges": [edge_meas("a", "ACT", 0.3, rer=0.6)], "snr": {"snr": 30.0}}, p, TOL)
    assert rows_of(c, "niirs")[0].passed is None and "ALT" in rows_of(c, "niirs")[0].reason
    edges = [edge_meas("a", "ACT", 0.3, rer=0.6), edge_meas("b", "ALT", 0.3, rer=0.5)]
    c = compare({"slanted_edges": edges, "snr": {"snr": None, "reason": "no patch"}}, p, TOL)
    assert rows_of(c, "niirs")[0].passed is None and "no patch" in rows_of(c, "niirs")[0].reason


# ---------------------------------------------------------------------------------------------- the system path


def test_predict_from_a_system_matches_the_system_otf_in_cycles_per_pixel(ankarasat3):
    from satchain.tf.budget import SystemOTF, mtf_at_nyquist

    truth = {"items": [edge_truth("act", 0.0), edge_truth("alt", 90.0)]}
    p = predict(ankarasat3, truth, otf=SystemOTF(ankarasat3), quality={"giqe5": 3.0})
    nyq = mtf_at_nyquist(ankarasat3)  # computed from the budget, in cy/mm at each axis' Nyquist
    assert p.edges["act"].mtf_at_nyquist == pytest.approx(nyq["act"], rel=1e-9)
    assert p.edges["alt"].mtf_at_nyquist == pytest.approx(nyq["alt"], rel=1e-9)


def test_local_predictions_leave_out_the_aerosol_adjacency_plateau(ankarasat3):
    """Aerosol adjacency puts a plateau 1 - s on every image frequency (its PSF spans ~200 m): the system MTF
    at Nyquist drops by exactly 1 - s, but an edge measured in a local ROI normalises that away, so the edge
    prediction is the one without adjacency."""
    from satchain.tf.budget import SystemOTF, mtf_at_nyquist

    s = 0.1
    hazy = ankarasat3.model_copy(
        update={"atmosphere": ankarasat3.atmosphere.model_copy(update={"aerosol_scattered_fraction": s})}
    )
    truth = {"items": [edge_truth("act", 0.0), edge_truth("alt", 90.0)]}
    clear = predict(ankarasat3, truth, otf=SystemOTF(ankarasat3), quality={"giqe5": 3.0})
    local = predict(hazy, truth, otf=SystemOTF(hazy), quality={"giqe5": 3.0})
    for axis in ("act", "alt"):
        assert mtf_at_nyquist(hazy)[axis] == pytest.approx((1 - s) * mtf_at_nyquist(ankarasat3)[axis], rel=1e-6)
        assert local.edges[axis].mtf_at_nyquist == pytest.approx(clear.edges[axis].mtf_at_nyquist, rel=1e-9)


def test_saturation_warning_names_the_target_and_its_electrons():
    class Sensor:
        full_well_e, offset_e, dark_e, electrons_per_unit = 1000.0, 10.0, 0.0, 1500.0

    truth = {
        "items": [{"id": "hot", "bright": 0.7}, {"id": "ok", "bright": 0.6}, {"id": "s", "mean": 0.4, "amplitude": 0.3}]
    }
    w = saturation_warnings(Sensor(), truth)
    assert len(w) == 2 and w[0].startswith("hot: reflectance 0.7 gives 1060 e-") and w[1].startswith("s:")


# ---------------------------------------------------------------------------------------------- property


@settings(max_examples=60, deadline=None)
@given(
    a=st.floats(0.2, 3.0),
    b=st.floats(0.2, 3.0),
    angle=st.floats(-45.0, 45.0),
    offset=st.floats(-0.05, 0.05).filter(lambda o: abs(abs(o) - 0.02) > 1e-9),
)
def test_edge_check_for_any_anisotropic_gaussian_and_any_edge_angle(a, b, angle, offset):
    """Prediction = exp(-(f/2)^2 (a^2 nx^2 + b^2 ny^2)) at Nyquist along the normal; pass iff |offset| <= tol."""
    t = math.radians(angle)
    nx, ny = math.cos(t), math.sin(t)
    p = predict_from_mtf(
        lambda fx, fy: np.exp(-((a * fx) ** 2) - (b * fy) ** 2), {"items": [edge_truth("e", angle)]}, gsd_m=1.0
    )
    exact = math.exp(-0.25 * ((a * nx) ** 2 + (b * ny) ** 2))
    assert p.edges["e"].mtf_at_nyquist == pytest.approx(exact, rel=1e-12, abs=1e-15)
    (row,) = rows_of(compare({"slanted_edges": [edge_meas("e", "ACT", exact + offset)]}, p, TOL), "edge_mtf_at_nyquist")
    assert row.error == pytest.approx(offset, abs=1e-12)
    assert row.passed is (abs(offset) <= TOL.edge_mtf_at_nyquist)
