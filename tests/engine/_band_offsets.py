"""Shared by tests/engine/test_bands_earth.py and test_bands_yaw.py: the textured scene whose bands' offsets they
measure, the budget's Earth-rotation offset of a band, and a band's content offset measured in one MS region."""

from __future__ import annotations

import numpy as np

from satchain.measure.registration import measure_registration
from satchain.prediction.budget import band_budgets
from satchain.scene.layout import Scene
from satchain.scene.targets import SlantedEdge

H, W = 40, 30  # the MS region measured (rows, cols)


def squares_scene() -> Scene:
    """4 m squares at random angles every 7 m: features of every orientation in every part of the window."""
    rng = np.random.default_rng(1)
    corners = [(x, y) for y in np.arange(2.0, 126.0, 7.0) for x in np.arange(2.0, 196.0, 7.0)]
    items = tuple(SlantedEdge(f"s{k}", center_m=(x + rng.uniform(0, 2), y + rng.uniform(0, 2)), size_m=4.0,
                              angle_deg=float(rng.uniform(-30, 30))) for k, (x, y) in enumerate(corners))  # fmt: skip
    return Scene(200.0, 130.0, items, 0.2)


def earth_px(system, name: str) -> tuple[float, float]:
    """Band ``name``'s predicted Earth-rotation offset from the reference band, (ALT, ACT) band px."""
    e = [b for b in band_budgets(system) if b["name"] == name][0]["registration"]["earth_rotation"]
    return e["alt_px"], e["act_px"]


def content_offset(reference: np.ndarray, image: np.ndarray, whole: tuple[int, int],
                   scale: int) -> tuple[float, float]:  # fmt: skip
    """``image``'s content offset from ``reference``'s (MS px): the region of ``image`` at (4, 32) against the
    reference's region ``whole`` MS px before it (offsets up to 1/4 of a region are measured), plus ``whole``."""
    kr, kc = whole
    r0, c0 = 4, 32  # the region's corner; with the tests' windows, inside the scene for every band
    ref = reference[scale * (r0 - kr) : scale * (r0 - kr + H), scale * (c0 - kc) : scale * (c0 - kc + W)]
    got = measure_registration(ref, image[r0 : r0 + H, c0 : c0 + W], scale=scale).offset_px
    return got[0] + kr, got[1] + kc
