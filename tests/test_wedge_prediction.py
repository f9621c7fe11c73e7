"""The wedge prediction: the measured scan and 15 % crossing on the wedge's noise-free predicted image (issue 18)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from satchain.comparison import compare
from satchain.config.run import Tolerances
from satchain.prediction.core import predict_from_mtf
from satchain.prediction.wedge import predict_wedge, wedge_model_image
from satchain.scene import HyperbolicWedge, Scene

GSD = 0.5
D = 8  # truth pixels per detector pixel
BG = 0.2


def _truth(orientation="horizontal", origin=(5.0, 4.0)):
    wedge = HyperbolicWedge(
        "w", origin_m=origin, orientation=orientation, length_m=50.0, line_width_start_m=2.0, line_width_end_m=0.2
    )
    scene = Scene(70.0, 70.0, (wedge,), background=BG, pixel_m=GSD / D)
    return scene, scene.truth()


def _box(f):
    """Transfer function of a centred mean over D consecutive fine samples, at f in cy per detector px."""
    f = np.asarray(f, float)
    den = D * np.sin(np.pi * f / D)
    return np.where(np.abs(den) < 1e-12, 1.0, np.sin(np.pi * f) / np.where(den == 0, 1.0, den))


def _block_mean(fine: np.ndarray) -> np.ndarray:
    h, w = fine.shape[0] // D, fine.shape[1] // D
    return fine[: h * D, : w * D].reshape(h, D, w, D).mean(axis=(1, 3))


@pytest.mark.parametrize("shift", [(0.0, 0.0), (0.5, 0.25)])
def test_model_image_is_the_detector_footprint_average(shift):
    """With an OTF that is exactly a D x D fine-pixel box, the model image must equal the block means of the
    truth rendered at the fine pixel: the window, sampling phase and pixel-grid convention are right."""
    scene, truth = _truth()
    (it,) = truth["items"]
    img, (ox, oy) = wedge_model_image(
        lambda fx, fy: _box(fx) * _box(fy), it, gsd_m=GSD, truth_pixel_m=GSD / D, background=BG, shift_px=shift
    )
    sx, sy = int(round(shift[0] * D)), int(round(shift[1] * D))
    r0, c0 = int(round(oy / GSD * D)) + sy, int(round(ox / GSD * D)) + sx
    fine = scene.render((r0, c0, img.shape[0] * D, img.shape[1] * D), pixel_m=GSD / D).astype(float)
    expect = _block_mean(fine)
    assert img.shape == expect.shape
    assert np.max(np.abs(img - expect)) < 1e-6
    assert expect.min() < 0.3 and expect.max() > 0.7  # the stripes are in the window


def _gauss(sigma_px):
    return lambda fx, fy: np.exp(-2 * np.pi**2 * sigma_px**2 * (fx**2 + fy**2)) * np.sinc(fx) * np.sinc(fy)


def test_prediction_is_not_clamped_and_grows_with_blur():
    """A blur wider than a pixel puts the crossing well beyond one GSD (the old prediction stayed at the GSD),
    and more blur resolves less; the placements' spread is small next to the blur's effect."""
    _, truth = _truth()
    (it,) = truth["items"]
    res = []
    for sigma in (0.8, 1.2):
        p = predict_wedge(_gauss(sigma), it, gsd_m=GSD, truth_pixel_m=GSD / D, background=BG)
        assert p.axis == "ALT" and p.resolution_m is not None
        assert len(p.resolutions_by_placement_m) == 4 and p.resolution_m_std is not None
        res.append(p.resolution_m)
    assert res[0] > 1.3 * GSD
    assert res[1] > res[0] + 0.1
    # the predicted contrast scan: from the wide end (first position), falling through the threshold
    assert p.position_m[0] < p.position_m[-1] and p.contrast[0] > p.threshold


def test_prediction_follows_the_axis_of_the_blur():
    """More blur along y (ALT): the horizontal wedge (resolves ALT) loses more resolution than the vertical (ACT)."""

    def aniso(fx, fy):
        return np.exp(-2 * np.pi**2 * (0.4**2 * fx**2 + 1.2**2 * fy**2)) * np.sinc(fx) * np.sinc(fy)

    out = {}
    for orientation in ("horizontal", "vertical"):
        _, truth = _truth(orientation)
        (it,) = truth["items"]
        out[orientation] = predict_wedge(aniso, it, gsd_m=GSD, truth_pixel_m=GSD / D, background=BG)
    assert out["horizontal"].axis == "ALT" and out["vertical"].axis == "ACT"
    assert out["horizontal"].resolution_m > out["vertical"].resolution_m + 0.2


def test_compare_uses_the_modelled_prediction_with_sigma():
    """compare() puts the modelled resolution, its predicted contrast curve and a sigma on the wedge row."""
    _, truth = _truth()
    truth = {**truth, "pixel_m": GSD / D}
    mtf = _gauss(0.8)
    pred = predict_from_mtf(mtf, truth, gsd_m=GSD)
    p = pred.wedges["w"]
    measured = {
        "hyperbolic_wedge": [
            {
                "id": "w",
                "orientation": "horizontal",
                "resolution_m": p.resolution_m * 1.05,
                "resolution_m_std": 0.02,
                "threshold": 0.15,
                "position_m_along_wedge": p.position_m.tolist(),
                "line_width_m": p.line_width_m.tolist(),
                "contrast": p.contrast.tolist(),
            },
            {"id": "w", "orientation": "horizontal", "resolution_m": None, "threshold": 0.15},
        ]
    }
    c = compare(measured, pred, Tolerances())
    rows = [r for r in c.rows if r.kind == "wedge_resolution"]
    assert rows[0].predicted == pytest.approx(p.resolution_m) and rows[0].error == pytest.approx(0.05)
    assert rows[0].passed is True
    # no noise model given: the sigma is the measurement's own 1-sigma of the crossing, relative
    assert rows[0].sigma == pytest.approx(0.02 / p.resolution_m)
    assert rows[1].passed is None and rows[1].sigma is None and rows[1].sigma_null_means
    w = c.hyperbolic_wedge[0]
    assert np.allclose(w.contrast_predicted, p.contrast)
    assert math.isclose(w.resolution_predicted_m, p.resolution_m)


def test_noise_sigma_of_the_crossing_agrees_with_repeated_noisy_measurements():
    """The parametric bootstrap's 1-sigma (16 noisy copies, fixed seed) against 40 independent noisy copies of
    the same predicted image measured by measure_auto; more noise, a wider spread; no noise, none."""
    from satchain.measure.auto import measure_auto
    from satchain.prediction.wedge import _WedgeModel

    _, truth = _truth()
    (it,) = truth["items"]
    otf = _gauss(0.8)
    kw = {"gsd_m": GSD, "truth_pixel_m": GSD / D, "background": BG, "placements_px": ((0.0, 0.0),)}
    sds = [predict_wedge(otf, it, noise_sigma=lambda r, k=k: k * (0.002 + 0.01 * r), **kw) for k in (0.0, 1.0, 3.0)]
    sds = [p.resolution_noise_m_std for p in sds]
    assert sds[0] == 0.0 and 0 < sds[1] < sds[2]
    model = _WedgeModel(otf, it, GSD, GSD / D, BG)
    img, rng = model.image((0.0, 0.0)), np.random.default_rng(7)
    res = []
    for _ in range(40):
        noisy = img + 3.0 * (0.002 + 0.01 * img) * rng.standard_normal(img.shape)
        (w,) = measure_auto(noisy, {"items": [it]}, pixel_m=GSD, origin_m=model.origin_m).to_dict()["hyperbolic_wedge"]
        res.append(w["resolution_m"])
    assert 0.6 < sds[2] / np.std(res, ddof=1) < 1.6


class _Cone:
    """A band-limited OTF (zero beyond ``cutoff`` cy/px), with or without advertising its cutoff."""

    def __init__(self, advertise: bool):
        if advertise:
            self.cutoff = 0.9

    def __call__(self, fx, fy):
        return np.clip(1.0 - np.hypot(fx, fy) / 0.9, 0.0, None) * np.sinc(fx) * np.sinc(fy)


def test_band_limited_otf_is_evaluated_in_its_band_only_with_the_same_image():
    """An OTF that advertises its cutoff is evaluated inside it only; the folded band gives the same samples
    (aliasing included) as the whole fine spectrum."""
    _, truth = _truth("vertical")
    (it,) = truth["items"]
    kw = {"gsd_m": GSD, "truth_pixel_m": GSD / D, "background": BG, "shift_px": (0.3, 0.6)}
    band, _ = wedge_model_image(_Cone(True), it, **kw)
    full, _ = wedge_model_image(_Cone(False), it, **kw)
    assert np.max(np.abs(band - full)) < 1e-9 and np.ptp(full) > 0.3
