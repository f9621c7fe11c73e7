"""Issue 29, item 12: the blur of a few rows as their line-of-sight paths are (``rows_blur_otf``), not the
budget's expectation over an oscillation's phase. Under Earth rotation the image drifts ACT by ``sigma`` px a
line during the TDI window (a box smear of ``N sigma`` px); a slow ACT oscillation adds its velocity on the rows
it is at: where it opposes the drift the smear is shorter (the issue's ACT bars, measured sharper than the
budget), where it adds, longer (its 10-degree edge)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from satchain import load_preset
from satchain.tf.pushbroom import PushbroomTerms
from satchain.tf.pushbroom_roi import per_row_otf, rows_blur_otf

EARTH = {"orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True}
F_HZ, AMP_PX = 60.0, 1.0


@pytest.mark.parametrize("velocity_sign", [1.0, -1.0])
def test_a_rows_smear_is_the_drift_plus_the_oscillations_velocity(velocity_sign):
    """At a zero crossing of the oscillation (its path there a straight line to third order) a row's window
    path is a line of slope ``sigma + 2 pi f A dt`` (+ or -) px a line: its transfer is ``|sinc(N slope nu)|``,
    closed form; the budget's expectation (``sinc(N sigma nu)`` times the oscillation's mean over phases) is not
    what that row has."""
    osc = {"axis": "act", "amplitude_px": AMP_PX, "frequency_hz": F_HZ}
    terms = PushbroomTerms(load_preset("ankarasat3").replace({**EARTH, "motion.oscillation": [osc]}))
    dt, n_st, sigma = terms.line_time_s, terms.stages, terms.drift_px[0]
    # a row whose window's middle is at a zero crossing going up (+) or down (-): sin(2 pi f t) = 0
    t_mid = (0.5 if velocity_sign < 0 else 1.0) / F_HZ
    row = int(round((t_mid - 0.5 * n_st * dt) / dt))
    t_mid = row * dt + 0.5 * n_st * dt
    slope = sigma + 2 * math.pi * F_HZ * AMP_PX * math.cos(2 * math.pi * F_HZ * t_mid) * dt
    nu = np.array([0.2, 0.33, 0.5])
    got = rows_blur_otf(terms, nu, "act", first_line=row, n_lines=1)
    np.testing.assert_allclose(got, np.abs(np.sinc(n_st * slope * nu)), atol=3e-3)
    budget = np.abs(per_row_otf(terms, nu, "act"))
    assert abs(got[2] - budget[2]) > 0.05  # the expectation over phases is not this row's blur


def test_without_oscillation_the_rows_blur_is_the_budgets():
    """A drift alone is the same on every row: the rows' blur is the budget's per-row term."""
    terms = PushbroomTerms(load_preset("ankarasat3").replace(EARTH))
    nu = np.linspace(0.05, 0.5, 10)
    got = rows_blur_otf(terms, nu, "act", first_line=100, n_lines=7)
    np.testing.assert_allclose(got, np.abs(per_row_otf(terms, nu, "act")), atol=2e-3)
