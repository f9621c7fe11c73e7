"""Real-world objects for NIIRS 2-8 interpretation tasks, at US-standard dimensions (metres).

Each object is drawn in a local frame ``(u, v)``: ``u`` along its length, ``v`` across, placed with
:func:`~satchain.scene.shapes.place` at ``origin_m`` and turned by ``rotation_deg`` (clockwise on
screen, since scene y points down). Dimensions and their sources:

* highway: 12 ft = 3.66 m lanes (AASHTO Green Book), 10 ft = 3.05 m shoulders; 6 in = 0.15 m lines;
  broken lane lines 10 ft = 3.05 m dashes with 30 ft = 9.14 m gaps (MUTCD 2009, section 3A.06);
  double yellow centre line with 0.10 m spacing.
* sedan 4.80 x 1.85 m, station wagon 4.90 x 1.85 m (full-size US cars); wipers 0.60 x 0.025 m.
* railway: standard gauge 1.435 m between the rails' inner faces; rail head 0.0746 m wide (AREMA
  136 RE); ties 2.59 x 0.229 m (8 ft 6 in x 9 in) at 0.495 m (19.5 in) centres; 4.0 m ballast bed.
* wagons: 50 ft boxcar 15.7 x 3.25 m body; tank car 17.9 m over heads, 3.0 m tank diameter.
* house: one-storey ranch 15.2 x 10.4 m (50 x 34 ft) gable roof, ridge along its length.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar

import numpy as np

from satchain._validate import check_choice, check_positive, check_range
from satchain.errors import ConfigError
from satchain.scene.base import Item, Layer, check_point, check_reflectance, tol_m
from satchain.scene.shapes import place, rectangle

__all__ = ["Car", "House", "Railway", "Road", "Wagon", "ellipse_arc"]


def ellipse_arc(cu: float, cv: float, au: float, av: float, a0: float, a1: float, *, tol: float) -> np.ndarray:
    """Points on ``(cu + au cos a, cv + av sin a)`` for a in [a0, a1], chords within ``tol`` of the arc.

    Examples
    --------
    >>> ellipse_arc(0, 0, 1, 1, 0, math.pi, tol=0.01)[[0, -1]].round(12).tolist()
    [[1.0, 0.0], [-1.0, 0.0]]
    """
    r = max(au, av)
    n = max(2, math.ceil(abs(a1 - a0) / (2 * math.acos(max(-1.0, 1.0 - tol / r)))) + 1)
    a = np.linspace(a0, a1, n)
    return np.stack([cu + au * np.cos(a), cv + av * np.sin(a)], axis=1)


class _Placed(Item):
    """Mixin: local polygons placed at ``origin_m`` turned by ``rotation_deg``."""

    origin_m: tuple[float, float]
    rotation_deg: float

    def _place(self, rings_local) -> list[np.ndarray]:
        return [place(r, self.origin_m, self.rotation_deg) for r in rings_local]

    @property
    def smallest_feature_m(self) -> float:
        """The narrower side of the object's footprint in its own frame (a car's width, a road's paved width)."""
        pts = np.concatenate([r for rings, _ in self.layers(0.01) for r in rings]) - np.asarray(self.origin_m)
        a = math.radians(self.rotation_deg)
        u = pts[:, 0] * math.cos(a) + pts[:, 1] * math.sin(a)
        v = -pts[:, 0] * math.sin(a) + pts[:, 1] * math.cos(a)
        return float(min(np.ptp(u), np.ptp(v)))

    def _check_placement(self, name: str):
        object.__setattr__(self, "origin_m", check_point(f"{name}.origin_m", self.origin_m))
        check_range(f"{name}.rotation_deg", self.rotation_deg, -360.0, 360.0)


@dataclasses.dataclass(frozen=True)
class Road(_Placed):
    """Two-way highway, ``lanes_per_direction`` lanes each way; ``origin_m``: start of its centre line."""

    kind: ClassVar[str] = "road"
    origin_m: tuple[float, float] = (0.0, 0.0)
    rotation_deg: float = 0.0
    length_m: float = 100.0
    lanes_per_direction: int = 2
    lane_width_m: float = 3.66
    shoulder_m: float = 3.05
    line_width_m: float = 0.15
    dash_m: float = 3.05
    gap_m: float = 9.14
    asphalt: float = 0.08
    shoulder: float = 0.12
    white: float = 0.75
    yellow: float = 0.5

    def __post_init__(self):
        self._check_placement("road")
        for name in ("length_m", "lane_width_m", "line_width_m", "dash_m", "gap_m"):
            check_positive(f"road.{name}", getattr(self, name))
        check_range("road.shoulder_m", self.shoulder_m, 0.0)
        if int(self.lanes_per_direction) != self.lanes_per_direction or self.lanes_per_direction < 1:
            raise ConfigError(f"road.lanes_per_direction = {self.lanes_per_direction!r}: must be an integer >= 1")
        for name in ("asphalt", "shoulder", "white", "yellow"):
            check_reflectance(f"road.{name}", getattr(self, name))

    @property
    def width_m(self) -> float:
        """Paved width including shoulders."""
        return 2 * (self.lanes_per_direction * self.lane_width_m + self.shoulder_m)

    def layers(self, pixel_m: float) -> list[Layer]:
        L, lw, n, half = self.length_m, self.line_width_m, self.lanes_per_direction, self.width_m / 2
        travel = n * self.lane_width_m
        surface = [rectangle(0, -half, L, half)]
        lanes = [rectangle(0, -travel, L, travel)]
        edges = [rectangle(0, -travel, L, -travel + lw), rectangle(0, travel - lw, L, travel)]
        yellow = [rectangle(0, -0.05 - lw, L, -0.05), rectangle(0, 0.05, L, 0.05 + lw)]
        starts = np.arange(0.0, L, self.dash_m + self.gap_m)
        dashes = []
        for k in range(1, n):
            for side in (-1, 1):
                c = side * k * self.lane_width_m
                dashes += [rectangle(s, c - lw / 2, min(s + self.dash_m, L), c + lw / 2) for s in starts]
        out = [(self._place(surface), self.shoulder), (self._place(lanes), self.asphalt)]
        out += [(self._place(edges), self.white), (self._place(yellow), self.yellow)]
        if dashes:
            out.append((self._place(dashes), self.white))
        return out

    def params(self) -> dict[str, Any]:
        return {
            "origin_m": list(self.origin_m),
            "rotation_deg": self.rotation_deg,
            "length_m": self.length_m,
            "width_m": self.width_m,
            "lanes_per_direction": self.lanes_per_direction,
            "lane_width_m": self.lane_width_m,
            "shoulder_m": self.shoulder_m,
            "line_width_m": self.line_width_m,
            "dash_m": self.dash_m,
            "gap_m": self.gap_m,
            "lane_centres_v_m": [
                (k + 0.5) * self.lane_width_m * s for s in (-1, 1) for k in range(self.lanes_per_direction)
            ],
        }


@dataclasses.dataclass(frozen=True)
class Car(_Placed):
    """Car seen from above: body, glass (windshield, rear window), wipers; front towards +u.

    ``model = "sedan"`` (4.80 x 1.85 m, trunk behind the rear window) or ``"station_wagon"``
    (4.90 x 1.85 m, roof to the tailgate, roof rails, rear wiper). ``origin_m`` is the car's centre.
    """

    kind: ClassVar[str] = "car"
    origin_m: tuple[float, float] = (0.0, 0.0)
    rotation_deg: float = 0.0
    model: str = "sedan"
    body: float = 0.55
    glass: float = 0.12
    wiper: float = 0.02

    def __post_init__(self):
        self._check_placement("car")
        check_choice("car.model", self.model, ("sedan", "station_wagon"))
        for name in ("body", "glass", "wiper"):
            check_reflectance(f"car.{name}", getattr(self, name))

    @property
    def size_m(self) -> tuple[float, float]:
        """(length, width)."""
        return (4.80, 1.85) if self.model == "sedan" else (4.90, 1.85)

    def _body(self, L, W):
        c = 0.25  # corner chamfer
        hl, hw = L / 2, W / 2
        return np.array(
            [
                [-hl + c, -hw],
                [hl - c, -hw],
                [hl, -hw + c],
                [hl, hw - c],
                [hl - c, hw],
                [-hl + c, hw],
                [-hl, hw - c],
                [-hl, -hw + c],
            ]
        )

    def layers(self, pixel_m: float) -> list[Layer]:
        L, W = self.size_m
        hw = W / 2
        windshield = np.array([[0.45, -0.70], [1.20, -0.82], [1.20, 0.82], [0.45, 0.70]])
        wipers = [self._wiper(1.12, -0.75), self._wiper(1.12, 0.0)]
        if self.model == "sedan":
            rear = np.array([[-1.45, -0.78], [-0.95, -0.68], [-0.95, 0.68], [-1.45, 0.78]])
            extras: list[Layer] = []
        else:
            rear = np.array([[-2.40, -0.62], [-2.05, -0.72], [-2.05, 0.72], [-2.40, 0.62]])
            wipers.append(self._wiper(-2.30, -0.30, length=0.40))
            rails = [
                rectangle(-1.95, -hw + 0.22, 0.35, -hw + 0.26),
                rectangle(-1.95, hw - 0.26, 0.35, hw - 0.22),
            ]
            extras = [(self._place(rails), self.wiper)]
        out = [(self._place([self._body(L, W)]), self.body), (self._place([windshield, rear]), self.glass)]
        return out + [(self._place(wipers), self.wiper)] + extras

    @staticmethod
    def _wiper(u, v, length=0.60, width=0.025):
        blade = rectangle(-width / 2, 0.0, width / 2, length)
        return place(blade, (u, v), -8.0)

    def params(self) -> dict[str, Any]:
        L, W = self.size_m
        return {
            "model": self.model,
            "origin_m": list(self.origin_m),
            "rotation_deg": self.rotation_deg,
            "length_m": L,
            "width_m": W,
            "wiper_size_m": [0.60, 0.025],
        }


@dataclasses.dataclass(frozen=True)
class Railway(_Placed):
    """Standard-gauge track on ballast; ``origin_m`` is the start of the track centre line."""

    kind: ClassVar[str] = "railway"
    origin_m: tuple[float, float] = (0.0, 0.0)
    rotation_deg: float = 0.0
    length_m: float = 100.0
    gauge_m: float = 1.435
    rail_head_m: float = 0.0746
    tie_length_m: float = 2.59
    tie_width_m: float = 0.229
    tie_spacing_m: float = 0.495
    ballast_width_m: float = 4.0
    ballast: float = 0.3
    tie: float = 0.18
    rail: float = 0.5

    def __post_init__(self):
        self._check_placement("railway")
        for name in (
            "length_m",
            "gauge_m",
            "rail_head_m",
            "tie_length_m",
            "tie_width_m",
            "tie_spacing_m",
            "ballast_width_m",
        ):
            check_positive(f"railway.{name}", getattr(self, name))
        if self.tie_width_m >= self.tie_spacing_m:
            raise ConfigError(f"railway.tie_width_m = {self.tie_width_m}: must be < tie_spacing_m")
        for name in ("ballast", "tie", "rail"):
            check_reflectance(f"railway.{name}", getattr(self, name))

    def tie_centres_u_m(self) -> np.ndarray:
        """Positions of tie centres along the track (m from the start)."""
        n = int(math.floor((self.length_m - self.tie_width_m) / self.tie_spacing_m)) + 1
        return self.tie_width_m / 2 + self.tie_spacing_m * np.arange(n)

    def layers(self, pixel_m: float) -> list[Layer]:
        L, g, r = self.length_m, self.gauge_m / 2, self.rail_head_m
        bed = [rectangle(0, -self.ballast_width_m / 2, L, self.ballast_width_m / 2)]
        tl, tw = self.tie_length_m / 2, self.tie_width_m / 2
        ties = [rectangle(u - tw, -tl, u + tw, tl) for u in self.tie_centres_u_m()]
        rails = [rectangle(0, -g - r, L, -g), rectangle(0, g, L, g + r)]
        return [
            (self._place(bed), self.ballast),
            (self._place(ties), self.tie),
            (self._place(rails), self.rail),
        ]

    def params(self) -> dict[str, Any]:
        return {
            "origin_m": list(self.origin_m),
            "rotation_deg": self.rotation_deg,
            "length_m": self.length_m,
            "gauge_m": self.gauge_m,
            "rail_head_m": self.rail_head_m,
            "rail_inner_faces_v_m": [-self.gauge_m / 2, self.gauge_m / 2],
            "tie_size_m": [self.tie_length_m, self.tie_width_m],
            "tie_spacing_m": self.tie_spacing_m,
            "n_ties": int(self.tie_centres_u_m().size),
        }


@dataclasses.dataclass(frozen=True)
class Wagon(_Placed):
    """Railway wagon seen from above; ``model = "boxcar"`` or ``"tank"``; ``origin_m`` is its centre."""

    kind: ClassVar[str] = "wagon"
    origin_m: tuple[float, float] = (0.0, 0.0)
    rotation_deg: float = 0.0
    model: str = "boxcar"
    body: float = 0.35
    detail: float = 0.15

    def __post_init__(self):
        self._check_placement("wagon")
        check_choice("wagon.model", self.model, ("boxcar", "tank"))
        check_reflectance("wagon.body", self.body)
        check_reflectance("wagon.detail", self.detail)

    @property
    def size_m(self) -> tuple[float, float]:
        """(body length, width)."""
        return (15.7, 3.25) if self.model == "boxcar" else (17.9, 3.0)

    def layers(self, pixel_m: float) -> list[Layer]:
        L, W = self.size_m
        hl, hw = L / 2, W / 2
        couplers = [rectangle(-hl - 0.6, -0.15, -hl, 0.15), rectangle(hl, -0.15, hl + 0.6, 0.15)]
        if self.model == "boxcar":
            body = [rectangle(-hl, -hw, hl, hw)]
            seams = [
                rectangle(u - 0.025, -hw + 0.05, u + 0.025, hw - 0.05) for u in np.arange(-hl + 1.3, hl - 1.0, 1.3)
            ]
            walk = [rectangle(-hl + 0.2, -0.25, hl - 0.2, 0.25)]
            return [(self._place(couplers + body), self.body), (self._place(seams + walk), self.detail)]
        tol = tol_m(pixel_m)
        head = 0.6
        right = ellipse_arc(hl - head, 0.0, head, hw, -math.pi / 2, math.pi / 2, tol=tol)
        left = ellipse_arc(-hl + head, 0.0, head, hw, math.pi / 2, 3 * math.pi / 2, tol=tol)
        tank = [np.concatenate([right, left])]
        platform = [rectangle(-1.2, -hw - 0.1, 1.2, hw + 0.1)]
        dome = [ellipse_arc(0.0, 0.0, 0.35, 0.35, 0.0, 2 * math.pi * (1 - 1e-9), tol=tol)[:-1]]
        return [
            (self._place(couplers + tank), self.body),
            (self._place(platform), self.detail),
            (self._place(dome), self.body),
        ]

    def params(self) -> dict[str, Any]:
        L, W = self.size_m
        return {
            "model": self.model,
            "origin_m": list(self.origin_m),
            "rotation_deg": self.rotation_deg,
            "length_m": L,
            "width_m": W,
        }


@dataclasses.dataclass(frozen=True)
class House(_Placed):
    """Gable-roofed house; the ridge runs along u; ``origin_m`` is the footprint's centre."""

    kind: ClassVar[str] = "house"
    origin_m: tuple[float, float] = (0.0, 0.0)
    rotation_deg: float = 0.0
    length_m: float = 15.2
    width_m: float = 10.4
    ridge_width_m: float = 0.3
    roof_lit: float = 0.4
    roof_shaded: float = 0.25
    ridge: float = 0.5

    def __post_init__(self):
        self._check_placement("house")
        for name in ("length_m", "width_m", "ridge_width_m"):
            check_positive(f"house.{name}", getattr(self, name))
        if self.ridge_width_m >= self.width_m:
            raise ConfigError(f"house.ridge_width_m = {self.ridge_width_m}: must be < width_m = {self.width_m}")
        for name in ("roof_lit", "roof_shaded", "ridge"):
            check_reflectance(f"house.{name}", getattr(self, name))

    def layers(self, pixel_m: float) -> list[Layer]:
        hl, hw, hr = self.length_m / 2, self.width_m / 2, self.ridge_width_m / 2
        return [
            (self._place([rectangle(-hl, -hw, hl, 0.0)]), self.roof_lit),
            (self._place([rectangle(-hl, 0.0, hl, hw)]), self.roof_shaded),
            (self._place([rectangle(-hl, -hr, hl, hr)]), self.ridge),
        ]

    def params(self) -> dict[str, Any]:
        return {
            "origin_m": list(self.origin_m),
            "rotation_deg": self.rotation_deg,
            "length_m": self.length_m,
            "width_m": self.width_m,
            "roof": "gable",
            "ridge_along": "u (length)",
        }
