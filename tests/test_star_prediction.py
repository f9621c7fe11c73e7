"""The Siemens-star prediction: the measured MTF on the star's noise-free predicted image (issue 18).

The images here are the test's own: the scene rendered at a fine pixel, filtered by a sampled Gaussian
(scipy.ndimage) and block-averaged to the detector pixel -- not the FFT model of satchain.prediction.target_image.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

import satchain
from satchain.comparison import compare, max_error_sigma
from satchain.config.run import RunConfig, Tolerances
from satchain.measure.auto import measure_auto
from satchain.prediction.core import predict_from_mtf
from satchain.prediction.target_image import TargetImageModel, item_from_truth
from satchain.scene import HyperbolicWedge, Scene, SiemensStar, SlantedEdge

GSD = 0.5
D = 8  # fine pixels per detector pixel
BG = 0.2
SIGMA_PX = 0.6  # Gaussian blur, 1-sigma in detector pixels


def _scene():
    star = SiemensStar("s", center_m=(52.0, 20.0), radius_m=16.0, cycles=32)
    edge = SlantedEdge("e", center_m=(14.0, 20.0), size_m=20.0, angle_deg=6.0)
    return Scene(72.0, 40.0, (edge, star), background=BG, pixel_m=GSD / D)


def _dirichlet(f):
    """Transfer function of the mean of D consecutive fine samples, at f in cy per detector px."""
    f = np.asarray(f, float)
    den = D * np.sin(np.pi * f / D)
    return np.where(np.abs(den) < 1e-12, 1.0, np.sin(np.pi * f) / np.where(den == 0, 1.0, den))


def _otf(sigma_px):
    """The OTF of the test's image formation (cy/px): Gaussian, then the D x D block mean."""

    def otf(fx, fy):
        g = np.exp(-2 * np.pi**2 * sigma_px**2 * (np.asarray(fx) ** 2 + np.asarray(fy) ** 2))
        return g * _dirichlet(fx) * _dirichlet(fy)

    return otf


def _image(scene, sigma_px):
    """The test's own image: fine render, sampled-Gaussian filter (wrapping: the border is background), block mean."""
    fine = ndimage.gaussian_filter(scene.render(), sigma_px * D, mode="wrap", truncate=5.0)
    h, w = fine.shape[0] // D, fine.shape[1] // D
    return fine[: h * D, : w * D].reshape(h, D, w, D).mean(axis=(1, 3))


@pytest.fixture(scope="module")
def setup():
    scene = _scene()
    truth = scene.truth()
    pred = predict_from_mtf(_otf(SIGMA_PX), truth, gsd_m=GSD)
    return scene, truth, pred, _image(scene, SIGMA_PX)


# ------------------------------------------------------------------------------------------------ model image


@pytest.mark.parametrize(
    "item",
    [
        SiemensStar("s", center_m=(30.0, 25.0), radius_m=12.0, cycles=24, inner_radius_m=0.8, mean=0.5, amplitude=0.3),
        SlantedEdge("e", center_m=(20.0, 20.0), size_m=18.0, angle_deg=-7.0, measures="alt", bright_side="negative"),
        HyperbolicWedge("w", origin_m=(5.0, 4.0), orientation="vertical", length_m=40.0),
    ],
)
def test_items_are_rebuilt_from_their_truth_records(item):
    assert item_from_truth(item.truth()) == item


def test_model_image_is_the_block_mean_of_the_fine_render_and_coarse_oversampling_agrees():
    """With the OTF of a D x D block mean the model is exactly the block means of the truth rendered at the fine
    pixel (window, phase, grid convention); with a Gaussian it agrees with the 4x-oversampled model."""
    scene = Scene(60.0, 45.0, (SiemensStar("s", center_m=(30.0, 22.0), radius_m=14.0),), background=BG, pixel_m=GSD / D)
    star = item_from_truth(scene.truth()["items"][0])
    m = TargetImageModel(lambda fx, fy: _dirichlet(fx) * _dirichlet(fy), star, gsd_m=GSD, truth_pixel_m=GSD / D,
                         background=BG)  # fmt: skip
    (c0, r0), (h, w) = m.origin_px, m.shape
    fine = scene.render(((r0 * D), (c0 * D), h * D, w * D), pixel_m=GSD / D)
    assert np.max(np.abs(m.image() - fine.reshape(h, D, w, D).mean(axis=(1, 3)))) < 1e-6
    kw = {"gsd_m": GSD, "truth_pixel_m": GSD / D, "background": BG}
    full = TargetImageModel(_otf(0.7), star, **kw).image()
    coarse = TargetImageModel(_otf(0.7), star, max_oversample=4, **kw).image()
    assert np.max(np.abs(full - coarse)) < 3e-3 and np.ptp(full) > 0.4


# ------------------------------------------------------------------------------------------------ prediction


def test_prediction_is_the_noise_free_measurement(setup):
    """The predicted MTF per direction is what measure_auto reads on the test's own noise-free image (the same
    calibration from the edge and the background, the same annuli); it differs from the system MTF by the
    estimator's systematic, which the comparison reports and no longer counts."""
    _, truth, pred, img = setup
    sp = pred.stars["s"]
    assert sp.reason is None and sp.input_modulation_from == "truth" and sp.calibration["fitted"]
    (meas,) = measure_auto(img, truth, pixel_m=GSD).to_dict()["siemens_star"]
    f = np.asarray(meas["f_cy_per_px"])
    for d in ("ACT", "ALT", "D45", "D135"):
        assert np.max(np.abs(sp.mtf_at(d, f) - np.asarray(meas["mtf"][d]))) < 1e-4, d
    (row,) = [r for r in compare({"siemens_star": [meas]}, pred, Tolerances()).rows if r.kind == "star_mtf"]
    assert abs(row.error) < 1e-4 and row.passed is True
    s = compare({"siemens_star": [meas]}, pred, Tolerances()).siemens_star[0]
    model = np.exp(-2 * np.pi**2 * SIGMA_PX**2 * f**2) * _dirichlet(f)  # the system MTF along ACT
    assert s.directions["ACT"]["mtf_model"] == pytest.approx(model, abs=1e-12)
    assert s.prediction.startswith("the star measured on its noise-free predicted image")
    assert s.estimator_systematic is not None and s.max_abs_error_to_model is not None
    assert row.model_prediction == pytest.approx(s.model_at_worst) and "estimator systematic" in row.note


def test_sigma_covers_the_noise_over_seeds(setup):
    """Noisy copies of the test's image: the star's error / sigma has a spread about 1 and a mean about 0 (the
    error is the largest of ~100 points, its sigma that of a maximum)."""
    _, truth, pred, img = setup
    rng = np.random.default_rng(2024)
    z = []
    for _ in range(12):
        noisy = img + 0.004 * rng.standard_normal(img.shape)
        (row,) = [r for r in compare(measure_auto(noisy, truth, pixel_m=GSD), pred, Tolerances()).rows
                  if r.kind == "star_mtf"]  # fmt: skip
        assert row.sigma is not None and row.passed is True
        z.append(row.z)
    z = np.asarray(z)
    assert abs(z.mean()) < 0.7 and 0.5 < z.std(ddof=1) < 1.5, z


def test_more_blur_than_predicted_fails_the_star(setup):
    scene, truth, pred, _ = setup
    blurred = _image(scene, 1.1)  # the camera blurs more than the design says
    (row,) = [r for r in compare(measure_auto(blurred, truth, pixel_m=GSD), pred, Tolerances()).rows
              if r.kind == "star_mtf"]  # fmt: skip
    assert row.passed is False and row.error < -0.05 and row.z < -5


def test_far_apart_targets_calibrate_on_the_background_and_no_prediction_falls_back_to_the_system_mtf(
    setup, monkeypatch
):
    """Stars and edges too far apart for one canvas: each star is formed alone, calibrated on the background (the
    prediction says so); a star whose predicted image cannot be measured is compared with the system MTF, and
    the detail says why."""
    from satchain.prediction import star as star_prediction
    _, truth, pred, img = setup
    monkeypatch.setattr(star_prediction, "MAX_CANVAS_PX", 100)
    p = predict_from_mtf(_otf(SIGMA_PX), truth, gsd_m=GSD).stars["s"]
    assert p.reason is None and "background alone" in p.calibration_note
    assert p.calibration["note"].startswith("one reflectance level")  # the background: offset assumed 0
    (meas,) = measure_auto(img, truth, pixel_m=GSD).to_dict()["siemens_star"]
    tiny = dict(truth, items=[dict(it, radius_m=2.0) if it["kind"] == "siemens_star" else it for it in truth["items"]])
    none = predict_from_mtf(_otf(SIGMA_PX), tiny, gsd_m=GSD)
    assert none.stars["s"].reason and "cannot be measured" in none.stars["s"].reason
    s = compare({"siemens_star": [meas]}, none, Tolerances()).siemens_star[0]
    assert s.prediction.startswith("the system MTF along each direction (")
    assert s.directions["ALT"]["mtf_predicted"] == s.directions["ALT"]["mtf_model"]
    assert s.estimator_systematic is None  # nothing measured on a predicted image: no systematic to report


def test_max_error_sigma_against_monte_carlo():
    """The 1-sigma of the signed largest of independent normal errors, against direct draws."""
    rng = np.random.default_rng(5)
    for sig in ([0.003], [0.002] * 30, list(np.linspace(0.001, 0.004, 40)), [0.001] * 50 + [0.02]):
        e = rng.standard_normal((20000, len(sig))) * np.asarray(sig)
        worst = e[np.arange(e.shape[0]), np.argmax(np.abs(e), axis=1)]
        assert max_error_sigma(sig) == pytest.approx(math.sqrt(np.mean(worst**2)), rel=0.03), sig
    assert max_error_sigma([np.nan, 0.0]) is None and max_error_sigma([0.01, np.nan]) == pytest.approx(0.01, rel=1e-5)


# ------------------------------------------------------------------------------------------------ end to end


def _run(tmp_path_factory, reduced_scene_toml, name, extra):
    d = tmp_path_factory.mktemp(name)
    (d / "scene.toml").write_text(reduced_scene_toml)
    cfg = RunConfig.from_dict({"scene": {"layout": "scene.toml", "pixel_m": 0.07}, **extra}, base_dir=d)
    return {r.kind: r for r in satchain.run(cfg).comparison.rows}["star_mtf"]


def test_run_star_z_is_modest_and_as_built_smear_fails_it(tmp_path_factory, reduced_scene_toml):
    design = _run(tmp_path_factory, reduced_scene_toml, "design", {})
    assert design.passed is True and abs(design.z) < 3 and design.model_prediction is not None
    built = _run(tmp_path_factory, reduced_scene_toml, "smear3", {"as_built": {"motion": {"smear_px": 3.0}}})
    assert built.passed is False and built.error < -0.1 and built.z < -3
