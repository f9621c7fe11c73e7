"""Bands under the Earth's rotation with yaw steering (satchain.engine.bands; issue 32 point 7): the detector turned
by ``gamma`` so that its columns follow the ground's relative motion. Each band still sees the ground at its own
time, but the ground then moves along the detector's columns only: the Earth's rotation leaves no ACT offset
between the bands, and an ALT one ``L (1 / a - 1)`` (``L`` the arrays' distance in lines, ``a = |(x, y)| / g`` the
relative speed per line over the GSD; the line rate is not matched to it). Measured
(:func:`satchain.measure.registration.measure_registration`) within 0.05 px of the budget's ``earth_rotation``
offset (:func:`satchain.prediction.budget.band_budgets`), with yaw steering on and off, noise-free, on a textured
scene. The ground truth is at 1/4 of a PAN pixel (the yaw's rotation needs the band below the coarse Nyquist)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _band_offsets import content_offset, earth_px, squares_scene

from satchain import load_preset
from satchain.engine.bands import simulate_bands
from satchain.prediction.budget import band_budgets
from satchain.scene.layout import Scene

P = 0.1225  # m: 4 scene px per PAN pixel, 16 per MS pixel
K = 16
#: The ground simulated (scene px: row0, col0, height, width): 48 x 64 MS px, the scene around it for the bands'
#: displaced grids (up to ~17 MS px ACT without yaw steering, ~5 ALT).
WINDOW = (16 * K, 36 * K, 48 * K, 64 * K)


def _system(latitude_deg: float, yaw: bool):
    earth = {"orbit.earth_rotation": True, "orbit.inclination_deg": 97.7, "orbit.yaw_steering": yaw}
    return load_preset("ankarasat3-pms").replace({**earth, "orbit.latitude_deg": latitude_deg})


@pytest.fixture(scope="module")
def scene() -> Scene:
    return squares_scene()


def test_the_budget_with_yaw_steering_has_no_act_offset_and_the_relative_speed_alt():
    """The closed form from the unsteered budget's own drift: steering turns ``(sigma, a)`` px a line into
    ``(0, |(sigma, a)|)`` (the GSDs ACT and ALT are equal here), so ``act = 0`` and ``alt = L (1 / |(sigma, a)| - 1)``,
    ``L`` the delay in band lines (unsteered: ``alt = L (1 / a - 1)``, ``act = -sigma L / a``)."""
    free, steered = band_budgets(_system(40.0, False)), band_budgets(_system(40.0, True))
    for f, s in zip(free[1:], steered[1:], strict=True):  # the MS bands (PAN's own offset is 0)
        e, lines = f["registration"]["earth_rotation"], f["registration"]["delay_lines"]
        a = 1.0 / (1.0 + e["alt_px"] / lines)
        sigma = -e["act_px"] * a / lines
        want_alt = lines * (1.0 / math.hypot(a, sigma) - 1.0)
        got = s["registration"]["earth_rotation"]
        assert got["act_px"] == 0.0
        assert got["alt_px"] == pytest.approx(want_alt, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize(("latitude_deg", "yaw"), [(40.0, True), (40.0, False), (0.0, True)])
def test_ms_band_offset_from_pan_matches_budget_with_and_without_yaw_steering(scene, latitude_deg, yaw):
    """Blue, 6 mm behind the PAN line, against PAN block-averaged onto the MS grid: within 0.05 px of the budget
    on both axes (measured: 40 deg steered (-2.572, 0.000) px for (-2.575, 0) predicted; unsteered (-2.273, 12.722)
    for (-2.261, 12.729); 0 deg steered (-2.793, 0.001) for (-2.803, 0)). Steered, the ACT offset is gone (and the
    yaw's turn of the lead is needed: leaving it out puts 0.13 px ACT, turning it the wrong way 0.26)."""
    system = _system(latitude_deg, yaw)
    want = earth_px(system, "blue")
    if yaw:
        assert want[1] == 0.0 and want[0] < -2.0
    else:
        assert abs(want[1]) > 10.0
    r = simulate_bands(scene, system, pixel_m=P, noise=False, bands=["pan", "blue"], window=WINDOW)
    got = content_offset(r["pan"].image, r["blue"].image, (round(want[0]), round(want[1])), 4)
    assert got == pytest.approx(want, abs=0.05), (got, want)


def test_two_ms_bands_with_yaw_steering_differ_by_the_difference_of_their_predictions(scene):
    """NIR (10.5 mm) against green (7.5 mm), steered, at 40 deg: within 0.05 px of the difference of their
    predictions."""
    system = _system(40.0, True)
    g, n = earth_px(system, "green"), earth_px(system, "nir")
    want = (n[0] - g[0], n[1] - g[1])
    r = simulate_bands(scene, system, pixel_m=P, noise=False, bands=["green", "nir"], window=WINDOW)
    got = content_offset(r["green"].image, r["nir"].image, (round(want[0]), round(want[1])), 1)
    assert got == pytest.approx(want, abs=0.05), (got, want)


@pytest.fixture(scope="module")
def texture():
    """A random texture band-limited to 0.3 cy per MS px (Gaussian roll-off, 0.2 cy/px), grey 0.3 +- 0.1: nothing
    aliases on the MS grid, so an offset is measured without the aliasing bias of sharp edges (on :func:`scene` a
    0.3 px ACT offset reads 0.310 even without the Earth's rotation), and a cache of each system's plain image."""
    from satchain.scene.image import ImageScene

    rng = np.random.default_rng(5)
    ny, nx = 1200, 1800  # scene px: the window and the bands' displaced grids (~20 MS px ACT unsteered)
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(ny) * K, np.fft.fftfreq(nx) * K, indexing="ij"))
    t = np.real(np.fft.ifft2(np.fft.fft2(rng.normal(size=(ny, nx))) * (f < 0.3) * np.exp(-((f / 0.2) ** 2))))
    return ImageScene((0.3 + 0.1 * t / t.std()).astype(np.float32), pixel_m=P), {}


def _texture_system(earth: str):
    if earth == "none":
        return _system(40.0, False).replace({"orbit.earth_rotation": False})
    return _system(40.0, earth == "yaw")


@pytest.mark.parametrize("earth", ["yaw", "unsteered", "none"])
@pytest.mark.parametrize("offset_px", [(0.3, 0.0), (0.0, 0.3), (-0.45, -0.2), (0.7, -1.35)])
def test_an_injected_offset_shows_as_given_under_yaw_steering(texture, earth, offset_px):
    """A band's registration_offset_px is what its image shows against the same band without it, in its own pixels,
    on both axes, within 0.005 px: steered (the ground turned by -2.9 deg and its rows 1.0102 GSD apart), unsteered
    (sheared -0.050 px ACT a line, rows 1.0089 apart) and without the Earth's rotation. The engine shifts the ground
    by the image's map of the offset (measured: every case within 0.0001 px; moving the ground by the offset itself
    showed 0.3 px ALT as (0.2967, 0.0150) steered and (0.2974, 0.0150) unsteered, 0.3 px ACT as (-0.0148, 0.2997)
    steered)."""
    scene, plain = texture
    system = _texture_system(earth)
    red = system.band_index("red")
    bands = tuple(b.model_copy(update={"registration_offset_px": offset_px}) if k == red else b
                  for k, b in enumerate(system.bands))  # fmt: skip
    moved = system.model_copy(update={"bands": bands})
    if earth not in plain:
        plain[earth] = simulate_bands(scene, system, pixel_m=P, noise=False, bands=["red"], window=WINDOW)["red"].image
    shifted = simulate_bands(scene, moved, pixel_m=P, noise=False, bands=["red"], window=WINDOW)["red"].image
    got = content_offset(plain[earth], shifted, (round(offset_px[0]), round(offset_px[1])), 1)
    assert got == pytest.approx(offset_px, abs=0.005), got
