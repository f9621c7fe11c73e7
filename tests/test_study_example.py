"""The packaged example study ``aperture-aberration`` (issue 31 point 5): its files, its cases, its findings
function, and one real run of its hardest case."""

from __future__ import annotations

import math

import pytest

from satchain.config.study import load_study
from satchain.errors import ConfigError
from satchain.studies.cases import expand_cases
from satchain.studies.examples import EXAMPLES, aperture_findings, example_path

AP, WFE = "optics.aperture_diameter_m", "optics.wfe_rms_waves"
APERTURES, WFES = (0.35, 0.45, 0.55, 0.70), (0.0, 0.05, 0.10)


@pytest.fixture(scope="module")
def study():
    return load_study(example_path("aperture-aberration"))


@pytest.fixture(scope="module")
def cases(study):
    return expand_cases(study)


def _gsd_m(system) -> float:
    """GSD = altitude x pitch / focal length (nadir), from the system's keys."""
    return system.orbit.altitude_m * system.detector.pitch_y_m / system.optics.focal_length_m


def _q(system) -> float:
    """Q = lambda N / p with N = f / D, from the system's keys (one wavelength in the reference camera)."""
    (lam,) = system.optics.wavelengths_m
    return lam * system.optics.focal_length_m / (system.optics.aperture_diameter_m * system.detector.pitch_y_m)


def test_every_example_is_packaged():
    for name, fname in EXAMPLES.items():
        path = example_path(name)
        assert path.name == fname and path.is_file()


def test_unknown_example_is_refused_naming_it_and_the_allowed():
    with pytest.raises(ConfigError, match=r"'no-such-study'.*aperture-aberration"):
        example_path("no-such-study")


def test_the_study_file(study):
    assert study.axis_values() == {AP: APERTURES, WFE: WFES}
    assert (study.study.depth, study.study.reports, study.study.repeats, study.study.zip) == ("run", "failed", 1, False)
    base = study.run_config()
    assert base.system.preset == "ankarasat3"
    # the scene file lies beside the study file and holds what the study measures, in both directions
    from pathlib import Path

    from satchain.scene.layout import load_layout

    layout = Path(base.layout_source())
    assert layout.parent == example_path("aperture-aberration").parent and layout.is_file()
    items = load_layout(layout).items
    edges = {it.measures for it in items if it.kind == "slanted_edge"}
    wedges = {it.orientation for it in items if it.kind == "hyperbolic_wedge"}
    assert edges == {"act", "alt"} and wedges == {"horizontal", "vertical"}


def test_cases_hold_the_gsd_while_f_number_and_q_grow(cases):
    assert len(cases) == 12
    assert sorted((c.values[AP], c.values[WFE]) for c in cases) == sorted((a, w) for a in APERTURES for w in WFES)
    focal = {c.system.optics.focal_length_m for c in cases}
    assert max(focal) - min(focal) < 1e-12  # varying the aperture holds the focal length
    by_aperture = {}
    for c in cases:
        s = c.system
        assert c.config is not None  # depth = "run": each case has its run configuration
        assert s.optics.aperture_diameter_m == pytest.approx(c.values[AP], rel=1e-12)
        assert s.optics.wfe_rms_waves == pytest.approx(c.values[WFE], abs=1e-12)
        assert _gsd_m(s) == pytest.approx(0.49, abs=5e-4)
        assert s.derived()["gsd_m"] == pytest.approx(_gsd_m(s), rel=1e-9)
        assert s.derived()["f_number"] == pytest.approx(s.optics.focal_length_m / c.values[AP], rel=1e-9)
        assert s.derived()["q_effective"] == pytest.approx(_q(s), rel=1e-9)
        by_aperture[c.values[AP]] = (s.derived()["f_number"], _q(s))
    # Q ~ 1 / D at a fixed focal length: 0.70 m (f/9.72, Q 1.07) to 0.35 m (f/19.4, Q 2.15)
    ordered = [by_aperture[a] for a in sorted(by_aperture, reverse=True)]
    assert all(b[0] > a[0] and b[1] > a[1] for a, b in zip(ordered, ordered[1:], strict=False))
    assert ordered[-1][1] == pytest.approx(2 * ordered[0][1], rel=1e-9)  # half the aperture, twice Q


# --- aperture_findings on synthetic rows --------------------------------------------------------------------

GSD, Q0 = 0.5, 1.0  # Q at 0.70 m; Q(D) = Q0 * 0.70 / D


def _q_of(a: float) -> float:
    return Q0 * 0.70 / a


def _rows(ratio_measured, ratio_predicted=None, *, direction="ALT", wfe=0.0, status="passed"):
    ratio_predicted = ratio_measured if ratio_predicted is None else ratio_predicted
    return [
        {
            AP: a,
            WFE: wfe,
            "case_status": status,
            "kind": "wedge_resolution",
            "figure": f"wedge wedge_{direction.lower()} resolution (m, {direction})",
            "check_id": f"wedge_{direction.lower()}",
            "measured": GSD * ratio_measured(a),
            "predicted": GSD * ratio_predicted(a),
            "gsd_m": GSD,
            "q": _q_of(a),
        }
        for a in APERTURES
    ]


def _finding(found, direction, wfe=0.0):
    (sentence,) = [s for t, s in found if t.startswith(direction) and f"WFE {wfe:g} " in t]
    return dict(part.split(": ", 1) for part in sentence.split("; "))


def test_findings_crossing_is_the_closed_form():
    # resolution / GSD = 1 + k (0.70 - D): departs by 10 % at D* = 0.70 - 0.10 / k, between two axis values
    k_meas, k_pred = 0.5, 0.8
    rows = _rows(lambda a: 1 + k_meas * (0.70 - a), lambda a: 1 + k_pred * (0.70 - a))
    found = aperture_findings(rows, {AP: APERTURES, WFE: (0.0,)})
    got = _finding(found, "ALT")
    for source, k in (("measured", k_meas), ("predicted", k_pred)):
        d_star = 0.70 - 0.10 / k
        lo, hi = max(a for a in APERTURES if a < d_star), min(a for a in APERTURES if a > d_star)
        t = (hi - d_star) / (hi - lo)  # Q interpolated linearly between the axis values, as the aperture is
        q_star = _q_of(hi) + t * (_q_of(lo) - _q_of(hi))
        assert got[source] == f"departs by more than 10 % below {d_star:.2f} m (Q = {q_star:.2f})"


def test_findings_below_the_gsd_and_both_directions():
    # a resolution that falls below the GSD as the aperture shrinks departs at ratio 0.90
    rows = _rows(lambda a: 1 - 0.4 * (0.70 - a), direction="ACT") + _rows(lambda a: 1.0, direction="ALT")
    found = aperture_findings(rows, [AP, WFE])
    d_star = 0.70 - 0.10 / 0.4  # 0.45: an axis value
    assert (
        _finding(found, "ACT")["measured"] == f"departs by more than 10 % below {d_star:.2f} m (Q = {_q_of(0.45):.2f})"
    )
    assert _finding(found, "ALT") == {"measured": "stays within 10 % down to 0.35 m"} | {
        "predicted": "stays within 10 % down to 0.35 m"
    }


def test_findings_read_the_direction_the_figure_names():
    # the figure's "(m, ALT)" decides, whatever the wedge's id says; without a figure, the id
    rows = [{**r, "check_id": "wedge_act_like"} for r in _rows(lambda a: 1.25, direction="ALT")]
    rows += [{**r, "figure": None} for r in _rows(lambda a: 1.0, direction="ACT")]
    found = aperture_findings(rows, [AP, WFE])
    assert _finding(found, "ALT")["measured"].startswith("departs by more than 10 % already")
    assert _finding(found, "ACT")["measured"] == "stays within 10 % down to 0.35 m"


def test_findings_never_and_already():
    rows = _rows(lambda a: 1.05, wfe=0.0) + _rows(lambda a: 1.25, wfe=0.1)
    found = aperture_findings(rows, {AP: APERTURES, WFE: (0.0, 0.1)})
    assert _finding(found, "ALT", 0.0)["measured"] == "stays within 10 % down to 0.35 m"
    assert _finding(found, "ALT", 0.1)["predicted"] == (
        f"departs by more than 10 % already at 0.70 m (Q = {_q_of(0.70):.2f})"
    )
    # the first finding quotes the largest aperture, smallest WFE: +5 %
    title, sentence = found[0]
    assert "0.70 m" in sentence and "+5 % measured" in sentence


def test_findings_average_repeats_and_skip_errored_cases():
    steep = _rows(lambda a: 1 + 0.5 * (0.70 - a))
    # a repeat that is 0.02 higher and one that is 0.02 lower average to the same crossing; an errored case
    # with an absurd value is left out
    up = [{**r, "measured": r["measured"] + 0.02 * GSD, "predicted": r["predicted"] + 0.02 * GSD} for r in steep]
    down = [{**r, "measured": r["measured"] - 0.02 * GSD, "predicted": r["predicted"] - 0.02 * GSD} for r in steep]
    bad = [{**r, "measured": 9.0, "case_status": "error"} for r in steep]
    assert aperture_findings(up + down + bad, [AP, WFE]) == aperture_findings(steep, [AP, WFE])


def test_findings_need_both_axes():
    rows = _rows(lambda a: 1.2)
    assert aperture_findings(rows, [AP]) == []
    assert aperture_findings(rows, {"optics.f_number": (8.0, 10.0), WFE: WFES}) == []
    assert aperture_findings([], [AP, WFE]) == []


# --- one real run: the smallest aperture with the largest WFE (the hardest case) -----------------------------


def test_hardest_case_runs_and_agrees(cases):
    import satchain

    (case,) = [c for c in cases if c.values[AP] == min(APERTURES) and c.values[WFE] == max(WFES)]
    cfg = case.config.to_dict()
    cfg["simulation"]["seed"] = case.seeds[0]  # the seed the study gives this case
    result = satchain.run(cfg)
    rows = result.comparison.rows
    wedges = {r.id: r for r in rows if r.kind == "wedge_resolution"}
    edges = {r.id: r for r in rows if r.kind == "edge_mtf_at_nyquist"}
    assert set(wedges) == {"wedge_act", "wedge_alt"} and set(edges) == {"edge_act", "edge_alt"}
    assert all(r.passed is True for r in (*wedges.values(), *edges.values()))
    for r in wedges.values():  # the modelled scan's prediction, within the run's tolerance
        assert abs(r.measured / r.predicted - 1) <= result.config.tolerances.wedge_resolution_rel
    b = satchain.budget(case.system)
    # Q > 2: the optics cut off below the detector's Nyquist, so the predicted MTF at Nyquist is 0 ...
    assert _q(case.system) > 2 and b.mtf_at_nyquist_act == 0 and b.mtf_at_nyquist_alt == 0
    # ... and what the edges measure there is noise, within 0.02 of it
    assert abs(edges["edge_act"].measured - b.mtf_at_nyquist_act) <= 0.02
    assert abs(edges["edge_alt"].measured - b.mtf_at_nyquist_alt) <= 0.02
    assert math.isfinite(wedges["wedge_act"].measured) and math.isfinite(wedges["wedge_alt"].measured)
