"""Off-nadir (across-track roll) geometry: slant range, incidence, foreshortened GSD, and its consequences."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain import ConfigError
from satchain.config.system import EARTH_RADIUS_M


@given(eta=st.floats(0.0, 60.0))
@settings(max_examples=30, deadline=None)
def test_slant_range_closes_the_earth_centred_triangle(ankarasat3, eta):
    o = ankarasat3.replace({"orbit.off_nadir_deg": eta}).orbit
    r, h = EARTH_RADIUS_M, o.altitude_m
    central = math.radians(o.incidence_deg - eta)  # Earth-central angle between nadir and target
    # law of cosines in the triangle (Earth centre, satellite, target)
    assert o.range_m**2 == pytest.approx((r + h) ** 2 + r**2 - 2 * r * (r + h) * math.cos(central), rel=1e-9)
    # law of sines: sin(incidence) / (R + h) = sin(eta) / R
    assert math.sin(math.radians(o.incidence_deg)) * r == pytest.approx((r + h) * math.sin(math.radians(eta)), abs=1e-6)
    assert o.elevation_deg == pytest.approx(90 - o.incidence_deg)


def test_nadir_and_small_angles(ankarasat3):
    o = ankarasat3.orbit
    assert o.range_m == o.altitude_m and o.incidence_deg == 0 and o.elevation_deg == 90
    s = ankarasat3.replace({"orbit.off_nadir_deg": 2.0})
    assert s.orbit.range_m == pytest.approx(567e3 / math.cos(math.radians(2)), rel=1e-3)  # near flat Earth


def test_ground_sampling_off_nadir(ankarasat3):
    s = ankarasat3.replace({"orbit.off_nadir_deg": 30.0})
    inc = math.radians(s.orbit.incidence_deg)
    assert s.gsd_alt_m == pytest.approx(5.88e-6 * s.orbit.range_m / 6.804)
    assert s.gsd_act_m == pytest.approx(s.gsd_alt_m / math.cos(inc))
    assert s.gsd_los_m == pytest.approx(s.gsd_alt_m)
    assert s.focal_cy_per_mm_per_ground_cy_per_m("act") == pytest.approx(s.gsd_act_m / 5.88e-6 / 1e3)
    with pytest.raises(ConfigError, match=r"orbit.off_nadir_deg = 70.0: must be below 66\.\d+ deg"):
        ankarasat3.replace({"orbit.off_nadir_deg": 70.0})


def test_niirs_falls_off_nadir(ankarasat3):
    from satchain.prediction.quality import predict_quality

    q0 = predict_quality(ankarasat3)
    q30 = predict_quality(ankarasat3.replace({"orbit.off_nadir_deg": 30.0}))
    assert q30.giqe5 < q0.giqe5 - 0.2  # longer range and a lower elevation
    # the MTF in cycles per pixel does not depend on the look angle, so neither do RER and overshoot
    assert q30.rer_act == pytest.approx(q0.rer_act) and q30.rer_alt == pytest.approx(q0.rer_alt)


def test_simulated_edge_off_nadir_has_the_nadir_mtf_per_pixel(ankarasat3):
    """Off nadir only the ground scale changes: an edge simulated at 30 deg (non-integer 19.6 input px per ACT
    pixel) and measured in cycles/pixel gives the predicted ACT MTF at Nyquist of the nadir system."""
    from satchain.engine.simulate import simulate
    from satchain.measure import measure_edge
    from satchain.tf.budget import mtf_at_nyquist

    s = ankarasat3.replace({"orbit.off_nadir_deg": 30.0})
    a = 0.035
    ny, nx = 2400, 3000
    yy, xx = np.mgrid[0:ny, 0:nx]
    angle = math.radians(5.0)  # near-vertical edge: measures ACT
    img = np.where((xx - nx / 2) * math.cos(angle) - (yy - ny / 2) * math.sin(angle) > 0, 0.8, 0.05)
    out = simulate(img, s, pixel_m=a)
    assert out.shape == (int(ny * a / s.gsd_alt_m), int(nx * a / s.gsd_act_m))
    r = measure_edge(out, roi=(20, 20, out.shape[1] - 20, out.shape[0] - 20))
    assert r.direction == "ACT"
    assert r.mtf_at_nyquist == pytest.approx(mtf_at_nyquist(ankarasat3)["act"], abs=0.01)
