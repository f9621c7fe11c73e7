"""Every check's 1-sigma: which measured uncertainty it is, z = error / sigma, "tolerance inside noise", and
signed errors that keep their sign when printed. Measurements are made up so every expected value is known."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.integrate import quad

from satchain.comparison import (
    NOISE_SIGMAS,
    REAL_DIFFERENCE_Z,
    SNR_REL_SIGMA,
    CheckRow,
    compare,
    max_error_sigma,
    row_texts,
    signed_text,
)
from satchain.config.run import Tolerances
from satchain.prediction.core import predict_from_mtf
from satchain.report.tables import fmt

TOL = Tolerances()


def gauss(fx, fy):
    return np.exp(-(fx**2) - (2 * fy) ** 2)


def row(error, sigma, tolerance=0.02):
    return CheckRow("f", "edge_mtf_at_nyquist", "e", None, None, error, tolerance, "±", None, None, sigma)


# ------------------------------------------------------------------------------------ z and noise marking


def test_z_is_error_over_sigma_and_absent_without_either():
    assert row(-0.006, 0.002).z == pytest.approx(-3.0)
    assert row(0.006, None).z is None and row(None, 0.002).z is None and row(0.006, 0.0).z is None


@pytest.mark.parametrize(
    ("tolerance", "sigma", "error", "inside"),
    [
        (0.004, 0.0041, 0.001, True),  # a +-0.004 tolerance against a 1-sigma of 0.0041: inside the noise
        (0.004, 0.004, 0.001, False),
        (0.008, 0.0041, 0.001, False),  # under 2 sigma but above 1: noise alone rarely decides it (was marked)
        (0.02, 0.004, 0.001, False),
        (0.02, None, 0.001, None),
        (0.05, 0.027, -0.265, False),  # issue 29: the star's FAIL at z -9.8 was marked "inside noise"
        (0.06, 0.073, 0.356, False),  # ... and the bars' at z +4.9 (tolerance < sigma, but |z| >= 3: real)
        (0.06, 0.073, 0.2, True),  # |z| 2.7: the same tolerance is inside the noise
    ],
)
def test_tolerance_inside_noise_only_below_one_sigma_and_never_at_a_real_difference(tolerance, sigma, error, inside):
    """Issue 29: "tolerance inside noise" only where the tolerance is smaller than the measurement's sigma, and
    never on a row whose |z| (>= 3) shows a real difference."""
    assert NOISE_SIGMAS == 1.0 and REAL_DIFFERENCE_Z == 3.0
    r = row(error, sigma, tolerance)
    assert r.tolerance_inside_noise is inside
    assert r.to_dict()["tolerance_inside_noise"] is inside
    assert ("tolerance inside noise" in row_texts(r)["result"]) is bool(inside)


# ------------------------------------------------------------------------------------ printed signs


def test_small_negative_error_keeps_its_sign():
    """NIIRS error -0.0039 printed "+0.00" before: never again, in the HTML and in the terminal."""
    assert fmt(-0.0039, 2, signed=True) == "-0.004"
    assert fmt(0.0039, 2, signed=True) == "+0.004"
    assert fmt(0.0, 2, signed=True) == "0.00"
    assert signed_text(-0.0039) == "-0.0039"
    assert row_texts(row(-0.0039, 0.004))["error"].startswith("-")


@given(st.floats(min_value=-10, max_value=10, allow_nan=False).filter(lambda x: x != 0), st.integers(0, 4))
def test_printed_error_has_the_sign_and_is_not_zero(x, digits):
    s = fmt(x, digits, signed=True)
    assert s[0] == ("-" if x < 0 else "+")
    assert float(s) != 0 and math.copysign(1, float(s)) == math.copysign(1, x)
    assert abs(float(s) - x) <= 0.5 * 10**-digits + 1e-12  # no coarser than asked
    assert abs(float(s) - x) <= 0.5 * abs(x) or abs(x) >= 0.5 * 10**-digits  # a tiny value keeps a digit


# ------------------------------------------------------------------------------------ sigma per check kind


def test_edge_mtf_sigma_is_the_measurement_sigma_and_angle_without_data_says_why():
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    e = {"id": "e", "direction": "ACT", "mtf_at_nyquist": 0.5, "mtf_at_nyquist_sigma": 0.003, "f_cy_per_px": [0.5],
         "mtf": [0.5], "angle_deg": 5.01, "angle_deg_truth": 5.0}  # fmt: skip
    c = compare({"slanted_edges": [e]}, p, TOL)
    mtf_row, angle_row = c.rows[0], c.rows[1]
    assert mtf_row.sigma == 0.003 and mtf_row.z == pytest.approx(mtf_row.error / 0.003)
    assert angle_row.sigma is None and "contrast-to-noise" in angle_row.sigma_null_means
    e["angle_deg_sigma"] = 0.004  # an edge result that reports its angle's sigma is used as it is
    assert compare({"slanted_edges": [e]}, p, TOL).rows[1].sigma == 0.004


def test_star_sigma_is_the_measured_sigma_at_the_worst_direction_and_frequency():
    f = np.array([0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    dirs = {"ACT": (1, 0), "ALT": (0, 1), "D45": (0.5**0.5, 0.5**0.5), "D135": (0.5**0.5, -(0.5**0.5))}
    mtf = {d: np.exp(-(f**2) * (ux**2 + (2 * uy) ** 2)) for d, (ux, uy) in dirs.items()}
    mtf["D45"][3] -= 0.03  # the worst error: D45 at 0.3 cy/px
    mtf["ACT"][6] += 0.5  # beyond Nyquist: not compared, its sigma irrelevant
    std = {d: (0.001 * (1 + np.arange(f.size))).tolist() for d in dirs}
    std["D45"][3] = 0.0123
    m = {"siemens_star": [{"id": "s", "f_cy_per_px": f.tolist(), "mtf": {d: v.tolist() for d, v in mtf.items()},
                           "mtf_std": std, "flags": ["uncertain centre"]}]}  # fmt: skip
    c = compare(m, predict_from_mtf(gauss, {"items": []}, gsd_m=1.0), TOL)
    (r,) = c.rows[:1]
    assert r.error == pytest.approx(-0.03, abs=1e-12)
    s = c.siemens_star[0]
    assert (s.worst_direction, s.worst_f_cy_per_px) == ("D45", 0.3) and s.flags == ["uncertain centre"]
    assert s.max_abs_error_sigma == 0.0123  # the measured 1-sigma at the worst point
    # the error is the largest of the 24 compared points (0.05..0.5 cy/px, 4 directions): its sigma is that of a
    # maximum, which the point of sigma 0.0123 dominates
    compared = [v for d in dirs for v in std[d][:6]]
    assert r.sigma == pytest.approx(max_error_sigma(compared), rel=1e-12) and 0.0123 < r.sigma < 0.0123 * 1.3


def test_bar_sigma_is_ctf_std_at_the_worst_group_and_raw_is_measured_minus_correction():
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=1.0)
    f = np.array([0.1, 0.2, 0.3])
    k = np.arange(100)[:, None]
    col = 4 / np.pi * np.sum((-1.0) ** k * np.exp(-(((2 * k + 1) * f) ** 2)) / (2 * k + 1), axis=0)
    ctf = col + np.array([0.01, -0.04, 0.02])
    b = {"id": "b", "direction": "ACT", "f_cy_per_px": f.tolist(), "ctf": ctf.tolist(),
         "ctf_std": [0.001, 0.017, 0.002], "ctf_correction": [-0.012, -0.02, None]}  # fmt: skip
    c = compare({"bar_targets": [b]}, p, TOL)
    r = c.rows[0]
    assert r.error == pytest.approx(0.04, abs=1e-9) and r.sigma == 0.017
    bc = c.bar_targets[0]
    assert bc.worst_f_cy_per_px == 0.2
    assert bc.ctf_raw_measured == pytest.approx([ctf[0] + 0.012, ctf[1] + 0.02, ctf[2]])


def giqe5_derivatives(rer, snr):
    """dNIIRS/dRER and dNIIRS/dSNR of GIQE 5, by hand."""
    lr, e = math.log10(rer), math.exp(-1.9 / snr)
    d_rer = (3.32 * (1 - e) - 8 * lr**3) / (rer * math.log(10))
    d_snr = 3.32 * lr * (-e * 1.9 / snr**2) + 1.8 / snr**2
    return d_rer, d_snr


def test_niirs_sigma_propagates_rer_and_snr_sigmas_through_giqe5():
    """Edges with a flat MTF 1-sigma s0 up to 1 cy/px bound their RER's 1-sigma by 2 s0 int_0^1 |sinc f| df;
    the two ACT edges average (sigma / sqrt 2); GIQE 5's RER (a^1 b^2)^(1/3) for a > b; SNR 1-sigma 5 %."""
    q = {"giqe5": 4.0, "rer_giqe5": 0.5, "snr": 40.0}
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=0.5, quality=q, gsd_los_m=0.55)
    f = np.linspace(0, 1, 201)
    s0 = 0.004

    def edge(eid, d, rer):
        return {"id": eid, "direction": d, "mtf_at_nyquist": 0.3, "rer": rer, "f_cy_per_px": f.tolist(),
                "mtf": np.ones_like(f).tolist(), "mtf_sigma": np.full(f.size, s0).tolist()}  # fmt: skip

    edges = [edge("a1", "ACT", 0.6), edge("a2", "ACT", 0.64), edge("l", "ALT", 0.45)]
    m = {"slanted_edges": edges, "snr": {"snr": 35.0}}
    r = compare(m, p, TOL).rows[-1]
    s_rer = 2 * s0 * quad(lambda x: abs(np.sinc(x)), 0, 1)[0]
    a, b, snr = 0.62, 0.45, 35.0
    rer = (a * b * b) ** (1 / 3)
    d_rer, d_snr = giqe5_derivatives(rer, snr)
    var = (d_rer * rer / (3 * a) * s_rer / math.sqrt(2)) ** 2 + (d_rer * 2 * rer / (3 * b) * s_rer) ** 2
    var += (d_snr * SNR_REL_SIGMA * snr) ** 2
    assert r.sigma == pytest.approx(math.sqrt(var), rel=2e-3)


def test_niirs_sigma_takes_the_measured_snr_sigma_and_notes_the_fallback():
    """With the SNR's own sigma, GIQE 5's SNR term carries it (no note); without, the assumed 5 % and a note."""
    q = {"giqe5": 4.0, "rer_giqe5": 0.5, "snr": 40.0}
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=0.5, quality=q, gsd_los_m=0.55)
    f = np.linspace(0, 1, 201)
    edges = [{"id": eid, "direction": d, "mtf_at_nyquist": 0.3, "rer": 0.5, "f_cy_per_px": f.tolist(),
              "mtf": np.ones_like(f).tolist(), "mtf_sigma": np.full(f.size, 1e-9).tolist()}
             for eid, d in (("a", "ACT"), ("l", "ALT"))]  # fmt: skip
    d_snr = giqe5_derivatives(0.5, 10.0)[1]
    for s_snr in (0.2, 1.5):
        c = compare({"slanted_edges": edges, "snr": {"snr": 10.0, "snr_sigma": s_snr}}, p, TOL)
        r = c.rows[-1]
        assert r.sigma == pytest.approx(abs(d_snr) * s_snr, rel=1e-3) and r.note is None
        assert c.niirs.snr_measured_sigma == s_snr
    why = "only 3 target-free background patch(es)"
    c = compare({"slanted_edges": edges, "snr": {"snr": 10.0, "snr_sigma": None, "snr_sigma_null_means": why}}, p, TOL)
    r = c.rows[-1]
    assert r.sigma == pytest.approx(abs(d_snr) * SNR_REL_SIGMA * 10.0, rel=1e-3)
    assert "assumed 5%" in r.note and why in r.note and c.niirs.snr_measured_sigma is None


def test_every_row_has_a_sigma_or_says_why():
    """A skipped target, an n/a check and a measurement without its uncertainty all say why sigma is null."""
    p = predict_from_mtf(gauss, {"items": []}, gsd_m=0.5)
    m = {
        "slanted_edges": [
            {"id": "e", "direction": "ALT", "mtf_at_nyquist": None, "f_cy_per_px": [], "mtf": []},
            {"id": "g", "direction": "ACT", "mtf_at_nyquist": 0.3, "f_cy_per_px": [0.5], "mtf": [0.3]},
        ],
        "skipped": [{"id": "x", "kind": "bar_target", "reason": "too small"}],
    }
    c = compare(m, p, TOL)
    for r in c.rows:
        assert (r.sigma is not None) != bool(r.sigma_null_means), r
    assert "no MTF sigma" in c.rows[2].sigma_null_means  # edge g, measured without its sigma
