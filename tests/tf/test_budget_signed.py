"""The budget prints a motion term's expected OTF with its sign (issue 29, item 11): an oscillation with whole
cycles in the TDI window has the expected OTF ``J0(2 pi nu A)``, negative past its first zero (it was printed as
its modulus, -0.237 as 0.237, while the quality line says ``signed_otf``)."""

from __future__ import annotations

import numpy as np
from scipy.special import j0

from satchain import load_preset, units
from satchain.prediction.budget import budget_results


def test_oscillation_column_is_the_signed_expected_otf():
    base = load_preset("ankarasat3")
    t_w = base.line_time_s * base.detector.tdi_stages
    osc = {"axis": "act", "amplitude_px": 1.5, "frequency_hz": 3.0 / t_w}  # 3 whole cycles in the window
    s = base.replace({"motion.oscillation": [osc]})
    nu = np.array([0.2, 0.35, 0.5])  # cy/px ACT: J0(2 pi nu 1.5) = 0.58, -0.18, -0.31
    res = budget_results(s, units.cy_per_px_to_cy_per_mm(nu, pitch_m=s.detector.pitch_x_m))
    col = np.asarray(res["mtf"]["act"]["oscillation_1"])
    np.testing.assert_allclose(col, j0(2 * np.pi * nu * 1.5), atol=1e-6)
    assert col[2] < -0.2 and np.all(np.asarray(res["mtf"]["act"]["system"]) >= 0)  # the system: its MTF
