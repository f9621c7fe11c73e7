"""Bands under the Earth's rotation (satchain.engine.bands; issue 32 point 7): with ``orbit.earth_rotation`` and no
yaw steering, each band sees the ground at its own time, so an MS band lies, from the PAN band (or from another MS
band), where the ground moved over the arrays' distance -- measured within 0.05 px of the budget's
``earth_rotation`` offset (:func:`satchain.prediction.budget.band_budgets`), noise-free, on a textured scene."""

from __future__ import annotations

import numpy as np
import pytest

from satchain import load_preset
from satchain.engine.bands import simulate_bands
from satchain.measure.registration import measure_registration
from satchain.prediction.budget import band_budgets
from satchain.scene.layout import Scene
from satchain.scene.targets import SlantedEdge

P = 0.245  # m: 2 scene px per PAN pixel, 8 per MS pixel (the engine's exact integer ratios)
#: The ground simulated (scene px: row0, col0, height, width): 48 x 64 MS px, the scene around it for the bands'
#: displaced grids (up to ~17 MS px ACT, ~3 ALT).
WINDOW = (16 * 8, 36 * 8, 48 * 8, 64 * 8)
H, W = 40, 30  # the MS region measured (rows, cols)


def _earth(latitude_deg: float):
    return load_preset("ankarasat3-pms").replace(
        {"orbit.earth_rotation": True, "orbit.latitude_deg": latitude_deg, "orbit.inclination_deg": 97.7}
    )


@pytest.fixture(scope="module")
def scene() -> Scene:
    """4 m squares at random angles every 7 m: features of every orientation in every part of the window."""
    rng = np.random.default_rng(1)
    corners = [(x, y) for y in np.arange(2.0, 126.0, 7.0) for x in np.arange(2.0, 196.0, 7.0)]
    items = tuple(SlantedEdge(f"s{k}", center_m=(x + rng.uniform(0, 2), y + rng.uniform(0, 2)), size_m=4.0,
                              angle_deg=float(rng.uniform(-30, 30))) for k, (x, y) in enumerate(corners))  # fmt: skip
    return Scene(200.0, 130.0, items, 0.2)


def _earth_px(system, name: str) -> tuple[float, float]:
    e = [b for b in band_budgets(system) if b["name"] == name][0]["registration"]["earth_rotation"]
    return e["alt_px"], e["act_px"]


def _offset(reference: np.ndarray, image: np.ndarray, whole: tuple[int, int], scale: int) -> tuple[float, float]:
    """``image``'s content offset from ``reference``'s (MS px): the region of ``image`` at (4, 32) against the
    reference's region ``whole`` MS px before it (offsets up to 1/4 of a region are measured), plus ``whole``."""
    kr, kc = whole
    r0, c0 = 4, 32  # the region's corner; with WINDOW, inside the scene for every band
    ref = reference[scale * (r0 - kr) : scale * (r0 - kr + H), scale * (c0 - kc) : scale * (c0 - kc + W)]
    got = measure_registration(ref, image[r0 : r0 + H, c0 : c0 + W], scale=scale).offset_px
    return got[0] + kr, got[1] + kc


@pytest.mark.parametrize("latitude_deg", [40.0, 0.0])
def test_ms_band_offset_from_pan_under_earth_rotation_matches_budget(scene, latitude_deg):
    """Blue, 6 mm behind the PAN line (1020 PAN lines; PAN 16 TDI stages, blue 1): its offset from PAN (PAN
    block-averaged onto the MS grid) within 0.05 px of the budget's earth_rotation prediction, both axes (measured:
    within 0.013 px at 40 deg, 0.008 at 0 deg; without the TDI windows' half-lengths in the band's own time the
    ACT offset is 0.10 px off). The prediction is large (12.7 / 16.7 px ACT, -2.3 px ALT), so the 1/a scale
    and the shear are checked, not only the sign."""
    system = _earth(latitude_deg)
    want = _earth_px(system, "blue")
    assert abs(want[1]) > 10.0 and want[0] < -2.0  # the content moves +x (ACT) and to earlier rows here
    r = simulate_bands(scene, system, pixel_m=P, noise=False, bands=["pan", "blue"], window=WINDOW)
    got = _offset(r["pan"].image, r["blue"].image, (round(want[0]), round(want[1])), 4)
    assert got == pytest.approx(want, abs=0.05), (got, want)


def test_two_ms_bands_differ_by_the_difference_of_their_predictions(scene):
    """NIR (10.5 mm) against green (7.5 mm) at 40 deg: the offset within 0.05 px of the difference of their
    earth_rotation predictions (measured: within 0.005 px)."""
    system = _earth(40.0)
    g, n = _earth_px(system, "green"), _earth_px(system, "nir")
    want = (n[0] - g[0], n[1] - g[1])
    r = simulate_bands(scene, system, pixel_m=P, noise=False, bands=["green", "nir"], window=WINDOW)
    got = _offset(r["green"].image, r["nir"].image, (round(want[0]), round(want[1])), 1)
    assert got == pytest.approx(want, abs=0.05), (got, want)
