"""A typed reader for the scene truth record (``*.truth.json``, ``Scene.truth()``).

:func:`read_truth` turns the JSON record into a frozen :class:`Truth` whose items are typed
(:class:`EdgeTruth`, :class:`StarTruth`, :class:`BarTargetTruth` with :class:`BarGroupTruth`,
:class:`WedgeTruth`, :class:`ObjectTruth` for roads, cars, ...). Positions are scene metres (x = ACT right,
y = ALT down); pixel regions are :class:`satchain.geometry.Rect` at the record's ``pixel_m``. Every key not
modelled is kept in ``extra``, so ``Truth.to_dict()`` gives back the record exactly (the measurement code
still takes the dict).

Examples
--------
>>> from satchain.scene import paper_layout
>>> t = read_truth(paper_layout().truth())
>>> [e.id for e in t.edges][:2], t.stars[0].cycles, t.bar_targets[0].groups[0].period_m
(['edge_act_5deg', 'edge_alt_5deg'], 32, 4.0)
>>> t.to_dict() == paper_layout().truth()
True
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from satchain.errors import InputError, SatchainIOError
from satchain.geometry import Rect
from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = [
    "BarGroupTruth",
    "BarTargetTruth",
    "EdgeTruth",
    "ObjectTruth",
    "StarTruth",
    "Truth",
    "TruthItem",
    "WedgeTruth",
    "read_truth",
]

_FORMAT_PREFIX = "satchain-scene-truth/"
BBox = tuple[float, float, float, float]


def _pair(v) -> tuple[float, float]:
    return (float(v[0]), float(v[1]))


def _bbox(v) -> BBox:
    return (float(v[0]), float(v[1]), float(v[2]), float(v[3]))


@dataclass(frozen=True)
class TruthItem:
    """Common fields: ``kind``, ``id``, ``bbox_m`` (xmin, ymin, xmax, ymax; m), ``bbox_px`` (the pixels the bbox
    touches), ``in_window``, and ``extra`` (every other key of the record, unchanged)."""

    kind: str
    id: str
    bbox_m: BBox
    bbox_px: Rect | None = None
    in_window: bool = True
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    @classmethod
    def _typed(cls) -> dict[str, Any]:
        return {}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> TruthItem:
        typed = cls._typed()
        try:
            kw = {k: conv(d[k]) for k, conv in typed.items() if k in d}
            missing = [k for k in typed if k not in d and k not in cls._optional()]
            if missing:
                raise KeyError(missing[0])
            base: dict[str, Any] = {"kind": str(d["kind"]), "id": str(d["id"]), "bbox_m": _bbox(d["bbox_m"])}
        except KeyError as exc:
            raise InputError(f"truth item {d.get('id', '?')!r} ({d.get('kind', '?')}): missing key {exc}") from None
        bbox_px = Rect.from_window(d["bbox_px"]) if "bbox_px" in d else None
        skip = {"kind", "id", "bbox_m", "bbox_px", "in_window", *typed}
        extra = {k: v for k, v in d.items() if k not in skip}
        return cls(**base, bbox_px=bbox_px, in_window=bool(d.get("in_window", True)), extra=extra, **kw)

    @classmethod
    def _optional(cls) -> tuple[str, ...]:
        return ()

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, "id": self.id, "bbox_m": list(self.bbox_m)}
        for f in fields(self):
            if f.name in ("kind", "id", "bbox_m", "bbox_px", "in_window", "extra"):
                continue
            v = getattr(self, f.name)
            if v is None and f.name in self._optional():
                continue
            out[f.name] = _plain(v)
        out.update(self.extra)
        if self.bbox_px is not None:
            out["bbox_px"] = list(self.bbox_px.to_window())
        out["in_window"] = self.in_window
        return out


def _plain(v):
    if isinstance(v, tuple):
        return [_plain(x) for x in v]
    if hasattr(v, "to_dict"):
        return v.to_dict()
    return v


@dataclass(frozen=True)
class EdgeTruth(TruthItem):
    """A slanted edge: ``measures`` ("act" | "alt"), ``angle_deg`` (truth convention), ``edge_point_m``,
    ``normal_to_bright`` (unit vector, x = ACT, y = ALT), ``bright`` / ``dark`` reflectances."""

    measures: str = "act"
    angle_deg: float = 0.0
    edge_point_m: tuple[float, float] = (0.0, 0.0)
    normal_to_bright: tuple[float, float] = (1.0, 0.0)
    bright: float = 1.0
    dark: float = 0.0

    @classmethod
    def _typed(cls):
        return {"measures": str, "angle_deg": float, "edge_point_m": _pair, "normal_to_bright": _pair,
                "bright": float, "dark": float}  # fmt: skip


@dataclass(frozen=True)
class StarTruth(TruthItem):
    """A Siemens star: ``center_m``, ``radius_m``, ``inner_radius_m``, ``cycles``, ``mean``, ``amplitude``."""

    center_m: tuple[float, float] = (0.0, 0.0)
    radius_m: float = 0.0
    inner_radius_m: float = 0.0
    cycles: int = 0
    mean: float = 0.0
    amplitude: float = 0.0

    @classmethod
    def _typed(cls):
        return {"center_m": _pair, "radius_m": float, "inner_radius_m": float, "cycles": int, "mean": float,
                "amplitude": float}  # fmt: skip


@dataclass(frozen=True)
class BarGroupTruth:
    """One bar group: ``period_m``, ``bar_width_m``, ``bar_length_m``, ``bbox_m``, ``bars_m`` (each bar's bbox)."""

    period_m: float
    bar_width_m: float
    bar_length_m: float
    bbox_m: BBox
    bars_m: tuple[BBox, ...]
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> BarGroupTruth:
        keys = ("period_m", "bar_width_m", "bar_length_m", "bbox_m", "bars_m")
        extra = {k: v for k, v in d.items() if k not in keys}
        return cls(float(d["period_m"]), float(d["bar_width_m"]), float(d["bar_length_m"]), _bbox(d["bbox_m"]),
                   tuple(_bbox(b) for b in d["bars_m"]), extra)  # fmt: skip

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"period_m": self.period_m}
        out.update({k: v for k, v in self.extra.items() if k == "f_cy_per_m_ground"})
        out.update({"bar_width_m": self.bar_width_m, "bar_length_m": self.bar_length_m,
                    "bbox_m": list(self.bbox_m), "bars_m": [list(b) for b in self.bars_m]})  # fmt: skip
        out.update(self.extra)
        return out


@dataclass(frozen=True)
class BarTargetTruth(TruthItem):
    """A bar target: ``orientation`` ("act" | "alt", the modulation axis), ``n_bars``, ``bright``, ``dark`` and
    its ``groups``."""

    orientation: str = "act"
    n_bars: int = 3
    bright: float = 1.0
    dark: float = 0.0
    groups: tuple[BarGroupTruth, ...] = ()

    @classmethod
    def _typed(cls):
        return {"orientation": str, "n_bars": int, "bright": float, "dark": float,
                "groups": lambda gs: tuple(BarGroupTruth.from_dict(g) for g in gs)}  # fmt: skip


@dataclass(frozen=True)
class WedgeTruth(TruthItem):
    """A hyperbolic wedge: ``orientation`` ("horizontal" | "vertical" | "diagonal"), ``local_origin_m``,
    ``length_m``, ``n_stripes``, ``line_width_start_m`` / ``line_width_end_m``, ``x0_m``, ``bright``, ``dark``."""

    orientation: str = "horizontal"
    local_origin_m: tuple[float, float] = (0.0, 0.0)
    length_m: float = 0.0
    n_stripes: int = 0
    line_width_start_m: float = 0.0
    line_width_end_m: float = 0.0
    x0_m: float = 0.0
    bright: float = 1.0
    dark: float = 0.0

    @classmethod
    def _typed(cls):
        return {"orientation": str, "local_origin_m": _pair, "length_m": float, "n_stripes": int,
                "line_width_start_m": float, "line_width_end_m": float, "x0_m": float, "bright": float,
                "dark": float}  # fmt: skip


@dataclass(frozen=True)
class ObjectTruth(TruthItem):
    """A real-world object (road, car, railway, wagon, house, ...): no measurement defined; ``origin_m`` and
    ``rotation_deg`` when the record has them."""

    origin_m: tuple[float, float] | None = None
    rotation_deg: float | None = None

    @classmethod
    def _typed(cls):
        return {"origin_m": _pair, "rotation_deg": float}

    @classmethod
    def _optional(cls):
        return ("origin_m", "rotation_deg")


_KINDS: dict[str, type[TruthItem]] = {
    SlantedEdge.kind: EdgeTruth,
    SiemensStar.kind: StarTruth,
    BarTarget.kind: BarTargetTruth,
    HyperbolicWedge.kind: WedgeTruth,
}


@dataclass(frozen=True)
class Truth:
    """The truth record: ``pixel_m`` (m), ``extent_m`` (width, height; m), ``window`` (the rendered region, a
    Rect at ``pixel_m``), ``background`` reflectance, and the typed ``items``."""

    format: str
    scene: str
    pixel_m: float
    extent_m: tuple[float, float]
    window: Rect
    background: float
    items: tuple[TruthItem, ...]
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def _of(self, cls) -> tuple:
        return tuple(it for it in self.items if type(it) is cls)

    @property
    def edges(self) -> tuple[EdgeTruth, ...]:
        return self._of(EdgeTruth)

    @property
    def stars(self) -> tuple[StarTruth, ...]:
        return self._of(StarTruth)

    @property
    def bar_targets(self) -> tuple[BarTargetTruth, ...]:
        return self._of(BarTargetTruth)

    @property
    def wedges(self) -> tuple[WedgeTruth, ...]:
        return self._of(WedgeTruth)

    @property
    def objects(self) -> tuple[ObjectTruth, ...]:
        return self._of(ObjectTruth)

    def __getitem__(self, item_id: str) -> TruthItem:
        for it in self.items:
            if it.id == item_id:
                return it
        raise KeyError(item_id)

    def to_dict(self) -> dict[str, Any]:
        """The JSON record (what ``Scene.truth()`` returns and measure_auto takes)."""
        out = {"format": self.format, "scene": self.scene, "pixel_m": self.pixel_m, "extent_m": list(self.extent_m)}
        out["shape_px"] = self.extra.get("shape_px")
        out["window_px"] = list(self.window.to_window())
        out["background"] = self.background
        out.update({k: v for k, v in self.extra.items() if k != "shape_px"})
        out["items"] = [it.to_dict() for it in self.items]
        return out


def read_truth(source: str | Path | Mapping[str, Any] | Truth) -> Truth:
    """Read a truth record from a ``.truth.json`` path or its dict into a typed :class:`Truth`."""
    if isinstance(source, Truth):
        return source
    data: Mapping[str, Any]
    if isinstance(source, Mapping):
        data = source
    else:
        p = Path(source)
        try:
            data = json.loads(p.read_text())
        except FileNotFoundError:
            raise SatchainIOError(f"truth file {str(p)!r}: not found") from None
        except json.JSONDecodeError as exc:
            raise InputError(f"truth file {str(p)!r}: not valid JSON ({exc})") from None
        except UnicodeDecodeError as exc:
            from satchain._safety import not_utf8

            raise not_utf8(p, exc, "truth file") from None
    d = dict(data)
    fmt = str(d.get("format", ""))
    if not fmt.startswith(_FORMAT_PREFIX):
        raise InputError(f"truth format = {fmt!r}: must be {_FORMAT_PREFIX}N (a satchain scene truth record)")
    try:
        items = tuple(_KINDS.get(it["kind"], ObjectTruth).from_dict(it) for it in d["items"])
        known = {"format", "scene", "pixel_m", "extent_m", "window_px", "background", "items"}
        return Truth(
            format=fmt,
            scene=str(d.get("scene", "")),
            pixel_m=float(d["pixel_m"]),
            extent_m=_pair(d["extent_m"]),
            window=Rect.from_window(d["window_px"]),
            background=float(d["background"]),
            items=items,
            extra={k: v for k, v in d.items() if k not in known},
        )
    except (KeyError, TypeError) as exc:
        raise InputError(f"truth record: missing or malformed key {exc}") from None
