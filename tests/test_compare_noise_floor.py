"""The edge MTF at Nyquist near zero (Q >= 2: the optics cut off at or below Nyquist): a measured MTF is the
magnitude of the transform plus its noise, so it reads the Rice mean of the prediction, not the prediction."""

from __future__ import annotations

import math

import numpy as np
import pytest

import satchain
from satchain.comparison._common import NOISE_FLOOR_SIGMAS, rice_mean
from satchain.studies.design import vary_system


@pytest.mark.parametrize("ratio", [0.0, 0.3, 1.0, 2.0, 3.0, 8.0])
def test_rice_mean_is_the_mean_magnitude_of_a_noisy_phasor(ratio):
    rng = np.random.default_rng(7)
    sigma = 0.0055
    nu = ratio * sigma
    z = nu + rng.normal(0, sigma, 400_000) + 1j * rng.normal(0, sigma, 400_000)
    assert rice_mean(nu, sigma) == pytest.approx(np.abs(z).mean(), rel=3e-3)
    assert rice_mean(nu, 0.0) == nu


def _run(tmp_path, scene: str, aperture_m: float, seed: int = 3):
    (tmp_path / "scene.toml").write_text(scene)
    base = satchain.load_preset("ankarasat3")
    system = vary_system(base, "optics.aperture_diameter_m", aperture_m)
    cfg = satchain.RunConfig.from_dict(
        {"system": {"inline": system.to_dict()}, "scene": {"layout": "scene.toml"}, "simulation": {"seed": seed}},
        base_dir=tmp_path,
    )
    (row,) = [r for r in satchain.run(cfg).comparison.rows if r.kind == "edge_mtf_at_nyquist"]
    return system, row


def test_q_above_2_compares_with_the_noise_floor(tmp_path, tiny_scene_toml):
    system, row = _run(tmp_path, tiny_scene_toml, 0.35)
    assert satchain.budget(system).q > 2  # the optics cut off below Nyquist: the model's MTF there is 0
    assert row.model_prediction == 0.0
    assert row.sigma is not None and row.predicted == pytest.approx(row.sigma * math.sqrt(math.pi / 2), rel=1e-12)
    assert row.error == pytest.approx(row.measured - row.predicted, abs=1e-15)
    assert "Rice mean" in (row.note or "")


def test_well_above_the_noise_the_prediction_is_the_model(tmp_path, tiny_scene_toml):
    _, row = _run(tmp_path, tiny_scene_toml, 0.70)
    assert row.model_prediction is None and row.sigma is not None
    assert row.predicted > NOISE_FLOOR_SIGMAS * row.sigma
    assert "Rice" not in (row.note or "")
