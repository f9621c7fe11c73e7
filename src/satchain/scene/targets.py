"""Standard image-quality targets: slanted edges, bar targets, hyperbolic wedges and a sine Siemens star.

All geometry is in scene metres (x right = ACT, y down = ALT, origin at the top-left corner of pixel
[0, 0]; see :mod:`satchain.scene.shapes`). Default sizes are chosen so each target can be measured at
the reference satellite's 0.49 m GSD (Alici et al., the reference paper, Figure 1):

* slanted edge: 60 m square (~120 GSD), tilt 5 deg (ISO 12233 recommends a few degrees);
* bar target: 3-bar groups (USAF-1951 style, bar length 5 bar widths) over a list of periods;
* hyperbolic wedge: five black stripes, line width 1.25 m at the wide end (line-pair width 2.5 m, as
  in the paper's Figure 4) falling as 1/s to 0.125 m over 60 m;
* Siemens star: 32 cycles, radius 20 m (the period reaches the 0.98 m Nyquist period at r = 5 m).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar

import numpy as np

from satchain._validate import check_choice, check_positive, check_range
from satchain.errors import ConfigError
from satchain.scene.base import Item, Layer, check_point, check_reflectance, tol_m
from satchain.scene.shapes import (
    Window,
    disc_vertices,
    hyperbola_vertices,
    rectangle,
    rings_coverage,
    sub_window,
)
from satchain.scene.star import sine_star_average

__all__ = ["BarTarget", "HyperbolicWedge", "SiemensStar", "SlantedEdge", "clip_half_plane"]


def clip_half_plane(vertices, point, normal) -> np.ndarray:
    """Part of a convex polygon where ``(v - point) . normal >= 0`` (one Sutherland-Hodgman pass).

    Examples
    --------
    >>> clip_half_plane([[0, 0], [2, 0], [2, 2], [0, 2]], (1, 0), (1, 0)).tolist()
    [[1.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, 2.0]]
    """
    v = np.asarray(vertices, dtype=float)
    d = (v - np.asarray(point, dtype=float)) @ np.asarray(normal, dtype=float)
    out = []
    for i in range(len(v)):
        j = (i + 1) % len(v)
        if d[i] >= 0:
            out.append(v[i])
        if (d[i] >= 0) != (d[j] >= 0):
            out.append(v[i] + (v[j] - v[i]) * (d[i] / (d[i] - d[j])))
    return np.array(out)


@dataclasses.dataclass(frozen=True)
class SlantedEdge(Item):
    """A square split by a straight edge through its centre, tilted from an image axis.

    ``measures = "act"``: the edge runs nearly along y (its direction is ``(sin a, cos a)``, i.e. +y
    turned by ``angle_deg`` towards +x) and the bright side is +x; it measures the ACT MTF.
    ``measures = "alt"``: the edge runs nearly along x (direction ``(cos a, sin a)``), bright side +y;
    it measures the ALT MTF. ``bright_side = "negative"`` swaps the sides.
    """

    kind: ClassVar[str] = "slanted_edge"
    center_m: tuple[float, float] = (30.0, 30.0)
    size_m: float = 60.0
    angle_deg: float = 5.0
    measures: str = "act"
    bright: float = 0.8
    dark: float = 0.05
    bright_side: str = "positive"

    def __post_init__(self):
        object.__setattr__(self, "center_m", check_point("slanted_edge.center_m", self.center_m))
        check_positive("slanted_edge.size_m", self.size_m)
        check_range("slanted_edge.angle_deg", self.angle_deg, -45.0, 45.0)
        check_choice("slanted_edge.measures", self.measures, ("act", "alt"))
        check_choice("slanted_edge.bright_side", self.bright_side, ("positive", "negative"))
        check_reflectance("slanted_edge.bright", self.bright)
        check_reflectance("slanted_edge.dark", self.dark)

    def _frame(self):
        a = math.radians(self.angle_deg)
        if self.measures == "act":
            direction, normal = (math.sin(a), math.cos(a)), (math.cos(a), -math.sin(a))
        else:
            direction, normal = (math.cos(a), math.sin(a)), (-math.sin(a), math.cos(a))
        if self.bright_side == "negative":
            normal = (-normal[0], -normal[1])
        return direction, normal

    def _square(self):
        cx, cy = self.center_m
        h = self.size_m / 2
        return rectangle(cx - h, cy - h, cx + h, cy + h)

    def layers(self, pixel_m: float) -> list[Layer]:
        _, normal = self._frame()
        return [
            ([self._square()], self.dark),
            ([clip_half_plane(self._square(), self.center_m, normal)], self.bright),
        ]

    def params(self) -> dict[str, Any]:
        direction, normal = self._frame()
        ends = clip_half_plane(self._square(), self.center_m, normal)
        on_edge = np.abs((ends - self.center_m) @ np.asarray(normal)) < 1e-9 * self.size_m
        return {
            "measures": self.measures,
            "angle_deg": self.angle_deg,
            "angle_definition": "edge direction = (+y if measures == 'act' else +x) turned by angle_deg "
            "towards (+x if 'act' else +y); x right (ACT), y down (ALT)",
            "edge_point_m": list(self.center_m),
            "edge_direction": list(direction),
            "normal_to_bright": list(normal),
            "edge_endpoints_m": ends[on_edge].tolist(),
            "size_m": self.size_m,
            "bright": self.bright,
            "dark": self.dark,
        }


@dataclasses.dataclass(frozen=True)
class BarTarget(Item):
    """A row of N-bar groups (bright bars on a dark plate), one group per period, left to right.

    ``orientation = "act"``: bars are long along y and repeat along x (they measure ACT);
    ``"alt"``: bars are long along x and repeat along y. Bar width is half the period, bar length
    ``length_factor`` bar widths (5, as USAF-1951), the plate extends one bar width around the bars,
    and groups are ``gap_m`` apart (default: the largest period), top-aligned at ``origin_m`` (top-left).
    """

    kind: ClassVar[str] = "bar_target"
    origin_m: tuple[float, float] = (0.0, 0.0)
    periods_m: tuple[float, ...] = (4.0, 3.0, 2.0, 1.5, 1.25, 1.0, 0.8, 0.6)
    n_bars: int = 3
    orientation: str = "act"
    length_factor: float = 5.0
    gap_m: float | None = None
    bright: float = 0.8
    dark: float = 0.05

    def __post_init__(self):
        object.__setattr__(self, "origin_m", check_point("bar_target.origin_m", self.origin_m))
        periods = tuple(float(check_positive("bar_target.periods_m", p)) for p in np.atleast_1d(self.periods_m))
        if not periods:
            raise ConfigError("bar_target.periods_m = (): must list at least one period")
        object.__setattr__(self, "periods_m", periods)
        if isinstance(self.n_bars, bool) or int(self.n_bars) != self.n_bars or self.n_bars < 1:
            raise ConfigError(f"bar_target.n_bars = {self.n_bars!r}: must be an integer >= 1")
        check_choice("bar_target.orientation", self.orientation, ("act", "alt"))
        check_positive("bar_target.length_factor", self.length_factor)
        if self.gap_m is not None:
            check_range("bar_target.gap_m", self.gap_m, 0.0)
        check_reflectance("bar_target.bright", self.bright)
        check_reflectance("bar_target.dark", self.dark)

    @property
    def smallest_feature_m(self) -> float:
        """The narrowest bar's width (half the shortest period), m."""
        return min(self.periods_m) / 2

    def groups(self) -> list[dict[str, Any]]:
        """Per period: plate and bar rectangles ``[xmin, ymin, xmax, ymax]`` (m)."""
        gap = max(self.periods_m) if self.gap_m is None else self.gap_m
        x, y0 = self.origin_m
        out = []
        for period in self.periods_m:
            b = period / 2
            along, across = (2 * self.n_bars - 1) * b, self.length_factor * b
            w, h = (along, across) if self.orientation == "act" else (across, along)
            bars = []
            for k in range(self.n_bars):
                s = 2 * k * b
                if self.orientation == "act":
                    bars.append([x + b + s, y0 + b, x + b + s + b, y0 + b + h])
                else:
                    bars.append([x + b, y0 + b + s, x + b + w, y0 + b + s + b])
            plate = [x, y0, x + w + 2 * b, y0 + h + 2 * b]
            out.append(
                {
                    "period_m": period,
                    "f_cy_per_m_ground": 1.0 / period,
                    "bar_width_m": b,
                    "bar_length_m": across,
                    "bbox_m": plate,
                    "bars_m": bars,
                }
            )
            x = plate[2] + gap
        return out

    def layers(self, pixel_m: float) -> list[Layer]:
        groups = self.groups()
        plates = [rectangle(*g["bbox_m"]) for g in groups]
        bars = [rectangle(*bar) for g in groups for bar in g["bars_m"]]
        return [(plates, self.dark), (bars, self.bright)]

    def params(self) -> dict[str, Any]:
        return {
            "orientation": self.orientation,
            "periodic_along": "x" if self.orientation == "act" else "y",
            "periods_m": list(self.periods_m),
            "n_bars": self.n_bars,
            "bright": self.bright,
            "dark": self.dark,
            "groups": self.groups(),
        }


@dataclasses.dataclass(frozen=True)
class HyperbolicWedge(Item):
    """Hyperbolic wedge (the paper's ``y = A_n / x`` construction, its Figure 4).

    Local frame: ``s`` along the wedge from its wide end (0 <= s <= length_m), ``t`` across it. With
    ``x0 = length / (w_start / w_end - 1)`` the boundaries are ``t_n(s) = A_n / (x0 + s)``,
    ``A_n = n * w_start * x0`` for ``n = 0 .. 2 N - 1``; stripe k (dark) lies between ``t_2k`` and
    ``t_2k+1``, so every line (dark or bright) has width ``w(s) = w_start * x0 / (x0 + s)`` (from
    ``w_start`` at s = 0 to ``w_end`` at s = length). The bright plate extends ``w_start`` beyond the
    pattern on every side. ``orientation = "horizontal"``: s along +x, t along +y (lines run along x,
    widths are measured along y: it resolves ALT); ``"vertical"``: s along +y, t along +x (resolves ACT);
    ``"diagonal"``: s along (1, 1)/sqrt2, t along (-1, 1)/sqrt2 (resolves the diagonal, the paper's future work).
    ``origin_m`` is the plate's top-left corner.
    """

    kind: ClassVar[str] = "hyperbolic_wedge"
    origin_m: tuple[float, float] = (0.0, 0.0)
    orientation: str = "horizontal"
    length_m: float = 60.0
    line_width_start_m: float = 1.25
    line_width_end_m: float = 0.125
    n_stripes: int = 5
    bright: float = 0.8
    dark: float = 0.05

    def __post_init__(self):
        object.__setattr__(self, "origin_m", check_point("hyperbolic_wedge.origin_m", self.origin_m))
        check_choice("hyperbolic_wedge.orientation", self.orientation, ("horizontal", "vertical", "diagonal"))
        check_positive("hyperbolic_wedge.length_m", self.length_m)
        check_positive("hyperbolic_wedge.line_width_start_m", self.line_width_start_m)
        check_range(
            "hyperbolic_wedge.line_width_end_m",
            self.line_width_end_m,
            0.0,
            self.line_width_start_m,
            lo_open=True,
            hi_open=True,
        )
        if isinstance(self.n_stripes, bool) or int(self.n_stripes) != self.n_stripes or self.n_stripes < 1:
            raise ConfigError(f"hyperbolic_wedge.n_stripes = {self.n_stripes!r}: must be an integer >= 1")
        check_reflectance("hyperbolic_wedge.bright", self.bright)
        check_reflectance("hyperbolic_wedge.dark", self.dark)

    @property
    def smallest_feature_m(self) -> float:
        """The narrowest line's width (at the narrow end), m."""
        return float(self.line_width_end_m)

    @property
    def x0_m(self) -> float:
        """Offset of the hyperbolas' asymptote from the wide end, m."""
        return self.length_m / (self.line_width_start_m / self.line_width_end_m - 1.0)

    def line_width_m(self, s_m):
        """Line width (one dark or bright line, half a period) at distance ``s_m`` from the wide end."""
        return self.line_width_start_m * self.x0_m / (self.x0_m + np.asarray(s_m, dtype=float))

    def _local_origin(self) -> tuple[float, float]:
        m = self.line_width_start_m
        return (self.origin_m[0] + m, self.origin_m[1] + m)

    def _to_scene(self, st: np.ndarray) -> np.ndarray:
        ox, oy = self._local_origin()
        s, t = st[:, 0], st[:, 1]
        if self.orientation == "horizontal":
            return np.stack([ox + s, oy + t], axis=1)
        if self.orientation == "diagonal":  # s along (1, 1)/sqrt2, t along (-1, 1)/sqrt2: resolves the diagonal
            r = np.sqrt(0.5)
            return np.stack([ox + r * (s - t), oy + r * (s + t)], axis=1)
        return np.stack([ox + t, oy + s], axis=1)

    def layers(self, pixel_m: float) -> list[Layer]:
        x0, w0, n = self.x0_m, self.line_width_start_m, self.n_stripes
        height = (2 * n - 1) * w0
        plate = rectangle(-w0, -w0, self.length_m + w0, height + w0)
        stripes = []
        for k in range(n):
            upper = hyperbola_vertices(2 * k * w0 * x0, x0, x0 + self.length_m, tol_m=tol_m(pixel_m))
            lower = hyperbola_vertices((2 * k + 1) * w0 * x0, x0, x0 + self.length_m, tol_m=tol_m(pixel_m))
            ring = np.concatenate([upper, lower[::-1]])
            ring[:, 0] -= x0
            stripes.append(self._to_scene(ring))
        return [([self._to_scene(plate)], self.bright), (stripes, self.dark)]

    def params(self) -> dict[str, Any]:
        x0, w0 = self.x0_m, self.line_width_start_m
        return {
            "orientation": self.orientation,
            "local_origin_m": list(self._local_origin()),
            "local_frame": "horizontal: x = ox + s, y = oy + t; vertical: x = ox + t, y = oy + s; "
            "diagonal: x = ox + (s - t)/sqrt2, y = oy + (s + t)/sqrt2",
            "length_m": self.length_m,
            "n_stripes": self.n_stripes,
            "line_width_start_m": w0,
            "line_width_end_m": self.line_width_end_m,
            "x0_m": x0,
            "boundary_A_m2": [n * w0 * x0 for n in range(2 * self.n_stripes)],
            "boundary_function": "t_n(s) = A_n / (x0_m + s), dark between t_2k and t_2k+1",
            "line_width_function": "line_width_m(s) = line_width_start_m * x0_m / (x0_m + s)",
            "frequency_function": "f_cy_per_m_ground(s) = (x0_m + s) / (2 * line_width_start_m * x0_m)",
            "bright": self.bright,
            "dark": self.dark,
        }


@dataclasses.dataclass(frozen=True)
class SiemensStar(Item):
    """Sinusoidal Siemens star: ``mean + amplitude * sin(cycles * theta)`` for ``inner <= r <= radius``.

    ``theta = atan2(y - cy, x - cx)`` (scene axes, clockwise on screen); inside ``inner_radius_m`` the
    star is uniform at ``mean`` (that centre cannot be resolved by any sampling, and is where the field is
    undefined). Pixel values are exact area averages (see :mod:`satchain.scene.star`).
    """

    kind: ClassVar[str] = "siemens_star"
    center_m: tuple[float, float] = (25.0, 25.0)
    radius_m: float = 20.0
    cycles: int = 32
    inner_radius_m: float = 1.0
    mean: float = 0.425
    amplitude: float = 0.375

    def __post_init__(self):
        object.__setattr__(self, "center_m", check_point("siemens_star.center_m", self.center_m))
        check_positive("siemens_star.radius_m", self.radius_m)
        check_range("siemens_star.inner_radius_m", self.inner_radius_m, 0.0, self.radius_m, lo_open=True, hi_open=True)
        if isinstance(self.cycles, bool) or int(self.cycles) != self.cycles or self.cycles < 1:
            raise ConfigError(f"siemens_star.cycles = {self.cycles!r}: must be an integer >= 1")
        check_reflectance("siemens_star.mean", self.mean)
        check_range("siemens_star.amplitude", self.amplitude, 0.0, min(self.mean, 1.0 - self.mean))

    def bbox_m(self) -> tuple[float, float, float, float]:
        (cx, cy), r = self.center_m, self.radius_m
        return (cx - r, cy - r, cx + r, cy + r)

    def layers(self, pixel_m: float) -> list[Layer]:
        return [([disc_vertices(self.center_m, self.radius_m, tol_m=tol_m(pixel_m))], self.mean)]

    def paint(self, image: np.ndarray, window: Window, pixel_m: float) -> None:
        sub = sub_window(self.bbox_m(), window, pixel_m)
        if sub is None:
            return
        disc = disc_vertices(self.center_m, self.radius_m, tol_m=tol_m(pixel_m))
        cov = np.clip(rings_coverage([disc], sub, pixel_m), 0.0, 1.0)
        wave = sine_star_average(
            sub,
            pixel_m=pixel_m,
            center_m=self.center_m,
            cycles=int(self.cycles),
            inner_radius_m=self.inner_radius_m,
            radius_m=self.radius_m,
        )
        r, c, sh, sw = sub
        view = image[r - window[0] : r - window[0] + sh, c - window[1] : c - window[1] + sw]
        view *= 1.0 - cov
        view += self.mean * cov + self.amplitude * wave

    def params(self) -> dict[str, Any]:
        return {
            "center_m": list(self.center_m),
            "radius_m": self.radius_m,
            "inner_radius_m": self.inner_radius_m,
            "cycles": int(self.cycles),
            "mean": self.mean,
            "amplitude": self.amplitude,
            "reflectance_function": "mean + amplitude * sin(cycles * theta), theta = atan2(y - cy, x - cx), "
            "inner_radius_m <= r <= radius_m; mean for r < inner_radius_m",
            "period_m_at_radius": "2 * pi * r / cycles",
        }
