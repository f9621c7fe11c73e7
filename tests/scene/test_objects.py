"""Real-world objects: US-standard dimensions, recovered from exact renders."""

from __future__ import annotations

import numpy as np
import pytest

from satchain.errors import ConfigError
from satchain.scene.objects import Car, House, Railway, Road, Wagon
from satchain.scene.shapes import polygon_area


def _render(item, shape, p):
    img = np.zeros(shape)
    item.paint(img, (0, 0, *shape), p)
    return img


def _runs_m(profile, p):
    """(start, end) in metres of runs of non-zero exact 1-D coverage (runs wider than one pixel)."""
    on = profile > 1e-12
    starts = np.flatnonzero(on & ~np.roll(on, 1))
    ends = np.flatnonzero(on & ~np.roll(on, -1))
    return [((j + 1 - profile[j]) * p, (k + profile[k]) * p) for j, k in zip(starts, ends, strict=True)]


def test_railway_gauge_ties_from_render():
    track = Railway("r", origin_m=(0.5, 3.0), length_m=10.0, ballast=0.0, tie=0.0, rail=1.0)
    p = 0.01
    img = _render(track, (600, 1100), p)
    col = img[:, int(5.0 / p)]  # a column across the track
    (a0, a1), (b0, b1) = _runs_m(col, p)
    assert b0 - a1 == pytest.approx(1.435, abs=1e-9)  # standard gauge between inner faces
    assert a1 - a0 == pytest.approx(0.0746, abs=1e-9)
    ties = Railway("r", origin_m=(0.5, 3.0), length_m=10.0, ballast=0.0, tie=1.0, rail=0.0)
    row = _render(ties, (600, 1100), p)[int(3.0 / p) + 110]  # 1.1 m from the centre line, between rails
    runs = _runs_m(row, p)
    starts = np.array([r[0] for r in runs])
    np.testing.assert_allclose(np.diff(starts), 0.495, atol=1e-9)
    np.testing.assert_allclose([r[1] - r[0] for r in runs], 0.229, atol=1e-9)
    assert track.truth()["n_ties"] == len(runs)


def test_road_lanes_and_dashes():
    road = Road("h", origin_m=(0.0, 12.0), length_m=30.0, asphalt=0.0, shoulder=0.0, white=1.0, yellow=0.0)
    p = 0.02
    img = _render(road, (1200, 1500), p)
    col = img[:, int(1.0 / p)]  # within the first dash
    runs = _runs_m(col, p)
    centres = np.array([(a + b) / 2 for a, b in runs]) - 12.0
    # edge lines, and dashed lines between the two lanes of each direction at +-3.66 m
    np.testing.assert_allclose(centres, [-7.32 + 0.075, -3.66, 3.66, 7.32 - 0.075], atol=1e-9)
    np.testing.assert_allclose([b - a for a, b in runs], 0.15, atol=1e-9)
    dash_row = img[int((12.0 + 3.66) / p)]
    dashes = _runs_m(dash_row, p)
    assert dashes[0][1] - dashes[0][0] == pytest.approx(3.05, abs=1e-9)
    assert dashes[1][0] - dashes[0][1] == pytest.approx(9.14, abs=1e-9)
    assert road.width_m == pytest.approx(2 * (2 * 3.66 + 3.05))


@pytest.mark.parametrize("model, length, width", [("sedan", 4.80, 1.85), ("station_wagon", 4.90, 1.85)])
def test_car_dimensions_and_body_area(model, length, width):
    car = Car("c", origin_m=(3.0, 2.0), model=model, body=1.0, glass=1.0, wiper=1.0)
    x0, y0, x1, y1 = car.bbox_m()
    assert (x1 - x0, y1 - y0) == (pytest.approx(length), pytest.approx(width))
    p = 0.01
    img = _render(car, (400, 600), p)
    chamfered = length * width - 4 * 0.25**2 / 2
    assert img.sum() * p * p == pytest.approx(chamfered, rel=1e-9)
    rotated = Car("c", origin_m=(3.0, 3.0), rotation_deg=90.0, model=model)
    x0, y0, x1, y1 = rotated.bbox_m()
    assert (x1 - x0, y1 - y0) == (pytest.approx(width), pytest.approx(length))
    # wipers exist and are thin, dark strips on the windshield
    rings, refl = car.layers(p)[2]
    assert len(rings) >= 2 and all(polygon_area(r) == pytest.approx(0.6 * 0.025) for r in rings[:2])


@pytest.mark.parametrize("model, length", [("boxcar", 15.7 + 1.2), ("tank", 17.9 + 1.2)])
def test_wagon_dimensions(model, length):
    x0, y0, x1, y1 = Wagon("w", origin_m=(20.0, 5.0), model=model).bbox_m()
    assert x1 - x0 == pytest.approx(length, abs=1e-6)  # body plus two 0.6 m couplers
    assert y1 - y0 == pytest.approx(3.25 if model == "boxcar" else 3.2, abs=1e-6)


def test_house_area_and_ridge():
    house = House("h", origin_m=(10.0, 8.0), roof_lit=1.0, roof_shaded=1.0, ridge=1.0)
    p = 0.05
    img = _render(house, (400, 400), p)
    assert img.sum() * p * p == pytest.approx(15.2 * 10.4, rel=1e-9)
    shaded = _render(House("h", origin_m=(10.0, 8.0), roof_lit=0.0, roof_shaded=1.0, ridge=0.0), (400, 400), p)
    assert shaded.sum() * p * p == pytest.approx(15.2 * (10.4 / 2 - 0.15), rel=1e-9)


@pytest.mark.parametrize(
    "cls, kwargs, match",
    [
        (Car, {"model": "truck"}, "model"),
        (Wagon, {"model": "flatcar"}, "model"),
        (Railway, {"tie_width_m": 0.6}, "tie_width_m"),
        (Road, {"lanes_per_direction": 0}, "lanes_per_direction"),
        (House, {"ridge_width_m": 20.0}, "ridge_width_m"),
        (Car, {"origin_m": (1.0,)}, "origin_m"),
    ],
)
def test_bad_object_parameters(cls, kwargs, match):
    with pytest.raises(ConfigError, match=match):
        cls("x", **kwargs)
