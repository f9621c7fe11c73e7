"""Exact area coverage of polygons and polygonised curves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain.errors import ConfigError, InputError
from satchain.scene.shapes import (
    check_window,
    disc_vertices,
    hyperbola_vertices,
    paint_polygon,
    place,
    polygon_area,
    polygon_coverage,
    rectangle,
)


def _star_polygon(rng, n, cx, cy, rmax):
    """Simple polygon, star-shaped about (cx, cy): angular gaps stay below pi."""
    ang = (np.arange(n) + rng.uniform(0, 0.45, n)) * (2 * np.pi / n)
    r = rng.uniform(0.2, 1.0, n) * rmax
    return np.stack([cx + r * np.cos(ang), cy + r * np.sin(ang)], axis=1)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(3, 40),
    pixel_m=st.floats(0.03, 2.0),
    reverse=st.booleans(),
)
def test_total_coverage_equals_polygon_area(seed, n, pixel_m, reverse):
    rng = np.random.default_rng(seed)
    v = _star_polygon(rng, n, 5.0, 6.0, 4.0)
    if reverse:
        v = v[::-1]
    rows = math.ceil(11.0 / pixel_m) + 2
    cov = polygon_coverage(v, (-1, -1, rows, rows), pixel_m=pixel_m)
    assert cov.min() >= 0.0 and cov.max() <= 1.0
    assert cov.sum() * pixel_m**2 == pytest.approx(polygon_area(v), rel=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    x0=st.floats(-3, 8),
    y0=st.floats(-3, 8),
    w=st.floats(0.01, 6),
    h=st.floats(0.01, 6),
    pixel_m=st.floats(0.1, 1.5),
)
def test_rectangle_coverage_is_product_of_overlaps(x0, y0, w, h, pixel_m):
    """Closed form: an axis-aligned rectangle covers |[x0,x1] & pixel_x| * |[y0,y1] & pixel_y| / p^2."""
    window = (-3, -4, 16, 17)
    cov = polygon_coverage(rectangle(x0, y0, x0 + w, y0 + h), window, pixel_m=pixel_m)
    cols = (window[1] + np.arange(window[3])) * pixel_m
    rows = (window[0] + np.arange(window[2])) * pixel_m
    ox = np.clip(np.minimum(cols + pixel_m, x0 + w) - np.maximum(cols, x0), 0, None)
    oy = np.clip(np.minimum(rows + pixel_m, y0 + h) - np.maximum(rows, y0), 0, None)
    np.testing.assert_allclose(cov, np.outer(oy, ox) / pixel_m**2, atol=1e-12)


def test_triangle_halves_a_pixel_and_half_plane_closed_form():
    # the diagonal triangle covers exactly half of the unit pixel
    cov = polygon_coverage([[0, 0], [1, 0], [0, 1]], (0, 0, 1, 1), pixel_m=1.0)
    assert cov[0, 0] == pytest.approx(0.5, abs=1e-15)
    # a large square cut by the line x = 0.3 + 0.2 y: row i covers the trapezoid left of the line
    big = np.array([[-10, -10], [0.3 - 2.0, -10], [0.3 + 2.0, 10], [-10, 10]])  # x_line(y) = 0.3 + 0.2 y
    cov = polygon_coverage(big, (0, 0, 3, 3), pixel_m=1.0)
    for i in range(3):
        xm = 0.3 + 0.2 * (i + 0.5)  # line position at the row centre (straight line: average = centre)
        expect = [min(max(xm - j, 0.0), 1.0) for j in range(3)]
        np.testing.assert_allclose(cov[i], expect, atol=1e-14)


def test_rotated_square_against_supersampling():
    v = place(rectangle(-1.3, -0.7, 1.3, 0.7), (2.1, 1.9), 33.0)
    p = 0.37
    cov = polygon_coverage(v, (0, 0, 11, 11), pixel_m=p)
    n = 300
    g = (np.arange(n) + 0.5) / n
    from matplotlib.path import Path

    path = Path(v)
    for i, j in [(5, 5), (2, 4), (7, 8), (3, 2), (6, 1)]:
        xx, yy = np.meshgrid((j + g) * p, (i + g) * p)
        ref = path.contains_points(np.c_[xx.ravel(), yy.ravel()]).mean()
        assert abs(cov[i, j] - ref) < 2e-3


@settings(max_examples=30, deadline=None)
@given(
    r0=st.integers(-5, 40),
    c0=st.integers(-5, 40),
    h=st.integers(1, 30),
    w=st.integers(1, 30),
)
def test_window_equals_crop(r0, c0, h, w):
    v = _star_polygon(np.random.default_rng(3), 25, 6.0, 5.0, 4.5)
    p = 0.3
    full = polygon_coverage(v, (-10, -10, 90, 90), pixel_m=p)
    win = polygon_coverage(v, (r0, c0, h, w), pixel_m=p)
    np.testing.assert_allclose(win, full[r0 + 10 : r0 + 10 + h, c0 + 10 : c0 + 10 + w], atol=1e-9)


def test_disc_area_and_pixel_accuracy():
    p = 0.25
    v = disc_vertices((2.0, 2.1), 1.3, tol_m=1e-4 * p)
    cov = polygon_coverage(v, (0, 0, 18, 18), pixel_m=p)
    assert cov.sum() * p * p == pytest.approx(math.pi * 1.3**2, rel=1e-9)
    n = 400
    g = (np.arange(n) + 0.5) / n
    for i, j in [(3, 8), (8, 3), (13, 8), (6, 6), (12, 12)]:  # boundary pixels
        xx, yy = np.meshgrid((j + g) * p, (i + g) * p)
        ref = (np.hypot(xx - 2.0, yy - 2.1) <= 1.3).mean()
        assert abs(cov[i, j] - ref) < 1.5e-3  # supersampling itself is good to ~1/n


def test_hyperbola_chords_within_tolerance():
    tol = 1e-4
    v = hyperbola_vertices(3.0, 0.5, 6.0, tol_m=tol)
    mid = (v[1:] + v[:-1]) / 2
    assert np.all(np.abs(mid[:, 1] - 3.0 / mid[:, 0]) <= tol)
    assert np.all(np.diff(v[:, 0]) > 0)


def test_paint_polygon_composes_in_painters_order():
    img = np.full((2, 2), 0.2)
    paint_polygon(img, rectangle(0.5, 0, 2, 2), 1.0, (0, 0, 2, 2), 1.0)
    np.testing.assert_allclose(img, [[0.6, 1.0], [0.6, 1.0]])
    paint_polygon(img, [rectangle(0, 0, 2, 1), rectangle(0, 1.5, 2, 2)], 0.0, (0, 0, 2, 2), 1.0)
    np.testing.assert_allclose(img, [[0.0, 0.0], [0.3, 0.5]])


@pytest.mark.parametrize("window", [(0, 0, 0, 5), (0, 0, 5), (0.5, 0, 2, 2), "abc", None])
def test_bad_windows(window):
    with pytest.raises(ConfigError, match="window"):
        check_window(window)


def test_bad_polygon_inputs():
    with pytest.raises(InputError, match="vertices_m"):
        polygon_coverage([[0, 0], [1, 1]], (0, 0, 2, 2), pixel_m=1.0)
    with pytest.raises(InputError, match="NaN"):
        polygon_coverage([[0, 0], [1, np.nan], [0, 1]], (0, 0, 2, 2), pixel_m=1.0)
    with pytest.raises(ConfigError, match="pixel_m"):
        polygon_coverage([[0, 0], [1, 0], [0, 1]], (0, 0, 2, 2), pixel_m=0.0)
