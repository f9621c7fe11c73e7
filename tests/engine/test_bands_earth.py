"""Bands under the Earth's rotation (satchain.engine.bands; issue 32 point 7): with ``orbit.earth_rotation`` and no
yaw steering, each band sees the ground at its own time, so an MS band lies, from the PAN band (or from another MS
band), where the ground moved over the arrays' distance -- measured within 0.05 px of the budget's
``earth_rotation`` offset (:func:`satchain.prediction.budget.band_budgets`), noise-free, on a textured scene. A
line-rate error (``motion.line_rate_error``) misregisters them the same way, along track: its ``line_rate``
offset."""

from __future__ import annotations

import pytest
from _band_offsets import content_offset, earth_px, squares_scene

from satchain import load_preset
from satchain.engine.bands import simulate_bands
from satchain.prediction.budget import band_budgets
from satchain.scene.layout import Scene

P = 0.245  # m: 2 scene px per PAN pixel, 8 per MS pixel (the engine's exact integer ratios)
#: The ground simulated (scene px: row0, col0, height, width): 48 x 64 MS px, the scene around it for the bands'
#: displaced grids (up to ~17 MS px ACT, ~3 ALT).
WINDOW = (16 * 8, 36 * 8, 48 * 8, 64 * 8)


def _earth(latitude_deg: float):
    return load_preset("ankarasat3-pms").replace(
        {"orbit.earth_rotation": True, "orbit.latitude_deg": latitude_deg, "orbit.inclination_deg": 97.7}
    )


@pytest.fixture(scope="module")
def scene() -> Scene:
    return squares_scene()


@pytest.mark.parametrize("latitude_deg", [40.0, 0.0])
def test_ms_band_offset_from_pan_under_earth_rotation_matches_budget(scene, latitude_deg):
    """Blue, 6 mm behind the PAN line (1020 PAN lines; PAN 16 TDI stages, blue 1): its offset from PAN (PAN
    block-averaged onto the MS grid) within 0.05 px of the budget's earth_rotation prediction, both axes (measured:
    within 0.013 px at 40 deg, 0.008 at 0 deg; without the TDI windows' half-lengths in the band's own time the
    ACT offset is 0.10 px off). The prediction is large (12.7 / 16.7 px ACT, -2.3 px ALT), so the 1/a scale
    and the shear are checked, not only the sign."""
    system = _earth(latitude_deg)
    want = earth_px(system, "blue")
    assert abs(want[1]) > 10.0 and want[0] < -2.0  # the content moves +x (ACT) and to earlier rows here
    r = simulate_bands(scene, system, pixel_m=P, noise=False, bands=["pan", "blue"], window=WINDOW)
    got = content_offset(r["pan"].image, r["blue"].image, (round(want[0]), round(want[1])), 4)
    assert got == pytest.approx(want, abs=0.05), (got, want)


def test_two_ms_bands_differ_by_the_difference_of_their_predictions(scene):
    """NIR (10.5 mm) against green (7.5 mm) at 40 deg: the offset within 0.05 px of the difference of their
    earth_rotation predictions (measured: within 0.005 px)."""
    system = _earth(40.0)
    g, n = earth_px(system, "green"), earth_px(system, "nir")
    want = (n[0] - g[0], n[1] - g[1])
    r = simulate_bands(scene, system, pixel_m=P, noise=False, bands=["green", "nir"], window=WINDOW)
    got = content_offset(r["green"].image, r["nir"].image, (round(want[0]), round(want[1])), 1)
    assert got == pytest.approx(want, abs=0.05), (got, want)


@pytest.mark.parametrize(("error", "earth"), [(2e-3, False), (-3e-3, False), (2e-3, True)])
def test_line_rate_error_misregisters_a_band_as_budgeted(scene, error, earth):
    """motion.line_rate_error: blue's offset from PAN within 0.05 px of the budget's line_rate (-0.51 px at 2e-3,
    +0.77 at -3e-3; measured within 0.004), and with the Earth's rotation at 40 deg of earth_rotation + line_rate
    (before the band's lead took the line rate in, blue lay 0.51 px from where the budget put it)."""
    system = (_earth(40.0) if earth else load_preset("ankarasat3-pms")).replace({"motion.line_rate_error": error})
    b = [x for x in band_budgets(system) if x["name"] == "blue"][0]["registration"]
    parts = [b["line_rate"], *([b["earth_rotation"]] if earth else [])]
    want = (sum(p["alt_px"] for p in parts), sum(p["act_px"] for p in parts))
    assert abs(b["line_rate"]["alt_px"]) > 0.5
    r = simulate_bands(scene, system, pixel_m=P, noise=False, bands=["pan", "blue"], window=WINDOW)
    got = content_offset(r["pan"].image, r["blue"].image, (round(want[0]), round(want[1])), 4)
    assert got == pytest.approx(want, abs=0.05), (got, want)
