"""Issue 29, item 14: the yaw's pivot is defined once (``tf.pushbroom.yaw_pivot_m``): the engine turns the ground
about the point ``image_affine`` turns it about, the detector grid's sub-pixel offset on the ground included.
Three Gaussian spots imaged under yaw steering land where the map of the simulator's grid puts them."""

import numpy as np
import pytest

from satchain import load_preset
from satchain.engine import yaw
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import ArraySource
from satchain.tf.pushbroom import PushbroomTerms

PX, N = 0.07, 700
YAW = load_preset("ankarasat3").replace(
    {"orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True, "orbit.yaw_steering": True}
)
SPOTS_M = [(12.0, 14.0), (36.0, 20.0), (20.0, 36.0)]


def _spots() -> np.ndarray:
    y, x = (np.mgrid[0:N, 0:N] + 0.5) * PX
    g = np.full((N, N), 0.2)
    for cx, cy in SPOTS_M:
        g += 0.6 * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * 0.6**2))
    return g


def _centroid(img: np.ndarray, col: float, row: float, half: int = 6) -> tuple[float, float]:
    r0, c0 = int(round(row)), int(round(col))
    w = np.clip(img[r0 - half : r0 + half + 1, c0 - half : c0 + half + 1] - 0.2, 0, None)
    yy, xx = np.mgrid[r0 - half : r0 + half + 1, c0 - half : c0 + half + 1]
    return float((w * xx).sum() / w.sum()), float((w * yy).sum() / w.sum())


@pytest.mark.parametrize("phase_px", [(0.0, 0.0), (3.5, 2.5)])
def test_the_engine_turns_the_ground_about_image_affines_pivot(phase_px):
    sim = Simulator(YAW, input_pixel_m=PX, input_shape=(N, N), params=SimParams(phase_px=phase_px))
    img = sim.run(ArraySource(_spots(), pixel_m=PX))
    mapped = yaw.image_affine(sim)
    plain = PushbroomTerms(YAW).image_affine(img.shape)  # the grid's offset left out
    assert abs(PushbroomTerms(YAW).geometry()["rotation_deg"]) > 3.5
    for spot in SPOTS_M:
        col, row = mapped @ spot
        mc, mr = _centroid(img, col, row)
        assert abs(mc - col) < 0.03 and abs(mr - row) < 0.03  # the PSF and the drift smear are symmetric
        if phase_px != (0.0, 0.0):
            pc, pr = plain @ spot
            assert np.hypot(mc - pc, mr - pr) > 0.3  # a map without the grid's offset misses it


def test_the_focal_plane_is_turned_as_the_image_is():
    """The focal-plane image under yaw steering is of the ground turned about the pivot (``B'(q) = B(P + M (q -
    P))``, README "Yaw steering"): each spot where that map puts it (it stayed on the unturned ground, 1 m
    away, before)."""
    sim = Simulator(YAW, input_pixel_m=PX, input_shape=(N, N))
    coarse = sim.decimate(ArraySource(_spots(), pixel_m=PX))
    fp = sim.focal_plane(coarse, grid="input")
    g = np.radians(PushbroomTerms(YAW).geometry()["rotation_deg"])
    m = np.array([[np.cos(g), np.sin(g)], [-np.sin(g), np.cos(g)]])
    rows, cols = sim.output_shape
    pivot = np.array([cols * YAW.gsd_act_m / 2, rows * YAW.gsd_alt_m / 2])
    for spot in SPOTS_M:
        q = pivot + np.linalg.solve(m, np.asarray(spot) - pivot)  # metres on the turned ground
        col, row = q / PX - 0.5  # input pixel centres
        mc, mr = _centroid(fp, col, row, half=40)
        assert np.hypot(mc - col, mr - row) < 0.1  # input pixels (7 mm)
        assert np.hypot(*(np.asarray(spot) - q)) > 0.7
