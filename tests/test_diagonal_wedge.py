"""The paper's future work: a diagonal hyperbolic wedge, rendered, simulated, measured and predicted."""

import math

import numpy as np
import pytest

from satchain.engine.sensor import sensor_from_system
from satchain.engine.simulate import simulate
from satchain.measure.auto import measure_auto
from satchain.prediction.core import predict
from satchain.scene import Scene
from satchain.scene.targets import HyperbolicWedge
from satchain.tf.budget import SystemOTF


def test_diagonal_wedge_geometry_is_the_horizontal_one_rotated_45_deg():
    h = HyperbolicWedge("h", origin_m=(0.0, 0.0), orientation="horizontal")
    d = HyperbolicWedge("d", origin_m=(0.0, 0.0), orientation="diagonal")
    r = math.sqrt(0.5)
    for (rh, _), (rd, _) in zip(h.layers(0.05), d.layers(0.05), strict=True):
        for ph, pd in zip(rh, rd, strict=True):
            o = np.array(h._local_origin())
            s, t = (ph - o).T
            np.testing.assert_allclose(pd, o + np.stack([r * (s - t), r * (s + t)], axis=1), atol=1e-9)
    assert d.params()["line_width_function"] == h.params()["line_width_function"]


@pytest.fixture(scope="module")
def measured(ankarasat3):
    items = (
        HyperbolicWedge("wd", origin_m=(20.0, 5.0), orientation="diagonal"),
        HyperbolicWedge("wh", origin_m=(5.0, 70.0), orientation="horizontal"),
    )
    sc = Scene(width_m=80, height_m=90, items=items, pixel_m=0.07)
    img = simulate(sc, ankarasat3, sensor=sensor_from_system(ankarasat3), units="dn", noise=True, seed=5)
    truth = sc.truth(pixel_m=0.07)
    res = measure_auto(img, truth, pixel_m=ankarasat3.gsd_m).to_dict()
    return {w["id"]: w for w in res["hyperbolic_wedge"]}, truth


def test_diagonal_resolution_against_prediction_and_sampling(ankarasat3, measured):
    ws, truth = measured
    pred = predict(ankarasat3, truth, otf=SystemOTF(ankarasat3), quality={}).wedges
    d, h = ws["wd"], ws["wh"]
    assert d["direction"] == "D135" and h["direction"] == "ALT"
    assert pred["wd"].axis == "D135" and pred["wh"].axis == "ALT"
    # the prediction is the same scan on the noise-free predicted image: the measured crossings sit within the
    # run's 15 % tolerance of it, and the diagonal (sampled sqrt(2) finer by a square grid) resolves finer
    # than the along-track wedge in both
    assert d["resolution_m"] == pytest.approx(pred["wd"].resolution_m, rel=0.15)
    assert h["resolution_m"] == pytest.approx(pred["wh"].resolution_m, rel=0.15)
    assert d["resolution_m"] < h["resolution_m"] and pred["wd"].resolution_m < pred["wh"].resolution_m
