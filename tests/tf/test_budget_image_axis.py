"""The prediction of a pushbroom image with a line-rate error is on the image's axis (issue 29, item 11): image
rows are ``1 + e`` detector pixels apart on the ground, so ``f`` cycles per image row are ``f / (1 + e)`` per
detector pixel.  Before, at the image's Nyquist: measured 0.1249 / 0.1082 / 0.0513 against 0.1213 / 0.0928 /
0.0287 for e = 0.01 / 0.05 / 0.1."""

from __future__ import annotations

import numpy as np
import pytest

from satchain import load_preset, simulate_image
from satchain.measure.edge import measure_edge
from satchain.prediction.core import AxisMTF, system_mtf_cy_per_px
from satchain.tf.budget import SystemOTF

BASE = load_preset("ankarasat3")


def _edge_scene(n_px: int, angle_deg: float, sub: int = 8) -> np.ndarray:
    """A near-horizontal step (normal near +y, ALT) at ``sub`` scene pixels per GSD."""
    n = sub * n_px
    y, x = np.mgrid[0:n, 0:n].astype(float)
    a = np.radians(angle_deg)
    return np.where((y - n / 2) * np.cos(a) - (x - n / 2) * np.sin(a) > 0, 0.6, 0.1)


@pytest.mark.parametrize("e", [0.01, 0.05, 0.1])
def test_alt_edge_mtf_predicted_on_the_images_axis(e):
    system = BASE.replace({"motion.line_rate_error": e})
    a = np.radians(5.0)
    img = simulate_image(_edge_scene(70, 5.0), system, pixel_m=BASE.gsd_m / 8).image
    r = measure_edge(img[5:-5, 5:-5])
    assert r.direction == "ALT"
    pred = AxisMTF(system_mtf_cy_per_px(SystemOTF(system), local=True), (np.sin(a), np.cos(a)))
    assert r.mtf_at_nyquist == pytest.approx(float(pred(0.5)), abs=0.004)
