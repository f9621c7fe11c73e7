"""Targets: edge angle/position, bar periods and wedge line widths recovered from renders."""

from __future__ import annotations

import math

import numpy as np
import pytest

from satchain.errors import ConfigError
from satchain.scene.layout import Scene
from satchain.scene.targets import BarTarget, HyperbolicWedge, SlantedEdge, clip_half_plane


def _render(item, width_m, height_m, p):
    """Float64 render on a zero background (Scene.render returns float32, ~1e-7 relative)."""
    shape = Scene(width_m, height_m, (item,)).shape_px(p)
    img = np.zeros(shape)
    item.paint(img, (0, 0, *shape), p)
    return img


@pytest.mark.parametrize("measures, angle", [("act", 5.0), ("alt", 5.0), ("act", 10.0), ("alt", -7.5)])
def test_edge_angle_and_position_recovered(measures, angle):
    """Per row (ACT) or column (ALT), the dark area left of/above the edge gives the edge position at the
    row centre exactly (area coverage); a line fit gives the angle and a point on the edge."""
    edge = SlantedEdge("e", center_m=(10.3, 9.7), size_m=16.0, angle_deg=angle, measures=measures,
                       bright=0.9, dark=0.1)  # fmt: skip
    p = 0.2
    img = _render(edge, 21.0, 20.0, p)
    if measures == "alt":
        img = img.T  # now rows run along x; the edge is near-vertical in this view
    lo = round(2.3 / p) if measures == "act" else round(2.0 / p)
    rows = np.arange(lo + 5, lo + 75)  # rows inside the square, away from its corners
    c0, c1 = round(2.5 / p), round(17.5 / p)  # inside the square in both views
    dark_frac = (0.9 - img[rows, c0:c1]) / 0.8
    pos_m = c0 * p + dark_frac.sum(axis=1) * p
    centre_m = (rows + 0.5) * p
    slope, intercept = np.polyfit(centre_m, pos_m, 1)
    assert math.degrees(math.atan(slope)) == pytest.approx(angle, abs=1e-7)
    t = edge.truth()
    px, py = t["edge_point_m"] if measures == "act" else t["edge_point_m"][::-1]
    assert slope * py + intercept == pytest.approx(px, abs=1e-8)
    # the 0.5 crossing of each row lies within half a pixel of the true edge
    norm = (img[rows, c0:c1] - 0.1) / 0.8
    cross = np.array([np.interp(0.5, r, (c0 + np.arange(r.size) + 0.5) * p) for r in norm])
    assert np.max(np.abs(cross - pos_m)) < 0.5 * p
    # bright side is along the recorded normal
    nx, ny = t["normal_to_bright"]
    cx, cy = t["edge_point_m"]
    bx, by = cx + 3 * nx, cy + 3 * ny
    assert _render(edge, 21.0, 20.0, p)[int(by / p), int(bx / p)] == pytest.approx(0.9)


def test_edge_truth_endpoints_on_square_border():
    edge = SlantedEdge("e", center_m=(0.0, 0.0), size_m=10.0, angle_deg=5.0)
    ends = np.array(edge.truth()["edge_endpoints_m"])
    assert ends.shape == (2, 2)
    np.testing.assert_allclose(np.abs(ends[:, 1]), 5.0)
    np.testing.assert_allclose(ends[:, 0], [-5 * math.tan(math.radians(5)), 5 * math.tan(math.radians(5))])


def _bar_edges_1d(profile, p):
    """Left edges (m) of bright runs from a 1-D exact coverage profile (runs wider than one pixel)."""
    on = profile > 1e-12
    starts = np.flatnonzero(on & ~np.roll(on, 1))
    return np.array([(j + 1) * p - profile[j] * p if profile[j] < 1 else j * p for j in starts])


@pytest.mark.parametrize("orientation", ["act", "alt"])
def test_bar_periods_recovered(orientation):
    periods = (2.0, 1.3, 0.9)
    bars = BarTarget("b", origin_m=(1.07, 0.93), periods_m=periods, orientation=orientation, bright=1.0, dark=0.0)
    p = 0.1
    img = _render(bars, 20.0, 20.0, p)
    if orientation == "alt":
        img = img.T
    for g in bars.truth()["groups"]:
        x0, y0, x1, y1 = g["bars_m"][0] if orientation == "act" else np.array(g["bars_m"][0])[[1, 0, 3, 2]]
        row = int((y0 + y1) / 2 / p)
        edges = _bar_edges_1d(img[row], p)
        inside = edges[(edges >= x0 - 1e-9) & (edges < x0 + 2.5 * g["period_m"])]
        assert inside.size == 3
        np.testing.assert_allclose(np.diff(inside), g["period_m"], atol=1e-9)
        assert inside[0] == pytest.approx(x0, abs=1e-9)
    # total bright area = n_bars * bar width * bar length per group
    total = sum(3 * g["bar_width_m"] * g["bar_length_m"] for g in bars.truth()["groups"])
    assert img.sum() * p * p == pytest.approx(total, rel=1e-9)


def test_bar_fft_period():
    bars = BarTarget("b", origin_m=(0.0, 0.0), periods_m=(1.0,), n_bars=12, bright=1.0, dark=0.0)
    p = 0.05
    img = _render(bars, 14.0, 4.0, p)
    row = img[int(1.5 / p), int(0.5 / p) : int(0.5 / p) + 200]  # 10 m of bars
    spec = np.abs(np.fft.rfft(row - row.mean()))
    f = np.fft.rfftfreq(row.size, d=p)
    assert f[np.argmax(spec)] == pytest.approx(1.0)


@pytest.mark.parametrize("orientation", ["horizontal", "vertical"])
def test_wedge_line_widths_follow_truth_function(orientation):
    wedge = HyperbolicWedge("w", origin_m=(0.5, 0.5), orientation=orientation, length_m=12.0,
                            line_width_start_m=0.8, line_width_end_m=0.2, bright=1.0, dark=0.0)  # fmt: skip
    p = 0.04
    img = _render(wedge, 15.0, 15.0, p)
    if orientation == "vertical":
        img = img.T  # s now runs along columns, t along rows
    t = wedge.truth()
    ox, oy = t["local_origin_m"] if orientation == "horizontal" else t["local_origin_m"][::-1]
    x0, w0, n = t["x0_m"], t["line_width_start_m"], t["n_stripes"]
    for s_m in (0.3, 3.0, 6.0, 9.0, 11.5):
        j = int((ox + s_m) / p)
        sa, sb = j * p - ox, (j + 1) * p - ox  # the column's extent along s
        mean_width = w0 * x0 * math.log((x0 + sb) / (x0 + sa)) / p  # average of w(s) over the column
        dark = 1.0 - img[:, j]
        rows = np.arange(int((oy - 0.3) / p), int((oy + (2 * n - 1) * w0 + 0.3) / p))
        d = dark[rows]
        on = d > 1e-9
        starts = np.flatnonzero(on & ~np.roll(on, 1))
        ends = np.flatnonzero(on & ~np.roll(on, -1))
        assert starts.size == n  # five separated dark stripes
        widths = np.array([d[a : b + 1].sum() * p for a, b in zip(starts, ends, strict=True)])
        np.testing.assert_allclose(widths, mean_width, rtol=2e-3)
        assert float(wedge.line_width_m((sa + sb) / 2)) == pytest.approx(mean_width, rel=1e-3)
    assert float(wedge.line_width_m(0.0)) == pytest.approx(0.8)
    assert float(wedge.line_width_m(12.0)) == pytest.approx(0.2)


def test_clip_half_plane_area():
    sq = [[0, 0], [2, 0], [2, 2], [0, 2]]
    part = clip_half_plane(sq, (1, 1), (1, 1))
    from satchain.scene.shapes import polygon_area

    assert polygon_area(part) == pytest.approx(2.0)


@pytest.mark.parametrize(
    "cls, kwargs, match",
    [
        (SlantedEdge, {"angle_deg": 60.0}, "angle_deg"),
        (SlantedEdge, {"measures": "diagonal"}, "measures"),
        (SlantedEdge, {"bright": 1.5}, "bright"),
        (BarTarget, {"periods_m": (1.0, -2.0)}, "periods_m"),
        (BarTarget, {"n_bars": 0}, "n_bars"),
        (HyperbolicWedge, {"line_width_end_m": 2.0}, "line_width_end_m"),
        (HyperbolicWedge, {"orientation": "oblique"}, "orientation"),
    ],
)
def test_bad_target_parameters(cls, kwargs, match):
    with pytest.raises(ConfigError, match=match):
        cls("x", **kwargs)
