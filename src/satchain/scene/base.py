"""The item interface shared by targets and objects, and the helpers that build items from dictionaries.

An item is a frozen dataclass with a ``kind`` (class attribute), an ``id`` and its geometry in scene
metres (see :mod:`satchain.scene.shapes` for the axes). It draws itself as an ordered list of
*layers* ``(rings, reflectance)``, composed in painter's order over what lies beneath:
``value = below * (1 - cov) + reflectance * cov``. Items that are smooth fields (the Siemens star)
override :meth:`Item.paint`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar

import numpy as np

from satchain._validate import check_range
from satchain.errors import ConfigError
from satchain.scene.shapes import DEFAULT_TOL_PX, Window, paint_polygon

__all__ = ["Item", "Layer", "check_reflectance", "check_point", "item_from_dict"]

Layer = tuple[list[np.ndarray], float]

#: pixel size used to build outlines when only the bounding box is wanted
_BBOX_PIXEL_M = 0.01


def check_reflectance(name: str, value: float) -> float:
    """Reflectance must be in [0, 1]."""
    return check_range(name, value, 0.0, 1.0)


def check_point(name: str, value) -> tuple[float, float]:
    """A finite ``(x, y)`` pair in metres."""
    try:
        x, y = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} = {value!r}: must be a pair (x, y) of numbers in metres") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ConfigError(f"{name} = {value!r}: must be finite")
    return (x, y)


@dataclasses.dataclass(frozen=True)
class Item:
    """Base class: subclasses define ``kind``, their fields, :meth:`layers` and :meth:`params`."""

    kind: ClassVar[str] = "item"
    id: str

    def layers(self, pixel_m: float) -> list[Layer]:
        """Ordered ``(rings, reflectance)``; curved outlines within ``DEFAULT_TOL_PX * pixel_m``."""
        raise NotImplementedError

    def params(self) -> dict[str, Any]:
        """Ground-truth parameters for measurement (JSON-serialisable, SI units)."""
        raise NotImplementedError

    def bbox_m(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` in scene metres."""
        rings = [r for rs, _ in self.layers(_BBOX_PIXEL_M) for r in rs]
        lo = np.min([r.min(axis=0) for r in rings], axis=0)
        hi = np.max([r.max(axis=0) for r in rings], axis=0)
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    def paint(self, image: np.ndarray, window: Window, pixel_m: float) -> None:
        """Compose this item over ``image`` (the rendered ``window``) in place; layers cull themselves."""
        for rings, refl in self.layers(pixel_m):
            paint_polygon(image, rings, refl, window, pixel_m)

    @property
    def smallest_feature_m(self) -> float | None:
        """The item's smallest dimension (m) that a scene raster must resolve, or None where it has none: a
        slanted edge (a step has no width) and a Siemens star (its spokes narrow to nothing by design; the star
        is measured only out to ``f_max``). Objects: the narrower side of their footprint; bar targets: the
        narrowest bar; wedges: the narrowest line (see :func:`satchain.scene.layout.check_scene_pixel`)."""
        return None

    def truth(self) -> dict[str, Any]:
        """``{"kind", "id", "bbox_m", **params}``."""
        return {"kind": self.kind, "id": self.id, "bbox_m": list(self.bbox_m()), **self.params()}


def tol_m(pixel_m: float) -> float:
    """Outline tolerance for curved shapes at a render pixel size."""
    return DEFAULT_TOL_PX * pixel_m


def _convert(value):
    if isinstance(value, list):
        return tuple(_convert(v) for v in value)
    return value


def item_from_dict(registry: dict[str, type[Item]], d: dict[str, Any], where: str = "item") -> Item:
    """Build an item from ``{"kind": ..., "id": ..., **fields}``; unknown keys are a ConfigError.

    Examples
    --------
    >>> from satchain.scene.targets import SlantedEdge
    >>> e = item_from_dict({"slanted_edge": SlantedEdge}, {"kind": "slanted_edge", "id": "e1",
    ...                    "center_m": [30, 30]})
    >>> e.angle_deg, e.size_m
    (5.0, 60.0)
    """
    if not isinstance(d, dict):
        raise ConfigError(f"{where} = {d!r}: must be a table/object with a 'kind'")
    kind = d.get("kind")
    if kind not in registry:
        raise ConfigError(f"{where}.kind = {kind!r}: must be one of {', '.join(map(repr, sorted(registry)))}")
    cls = registry[kind]
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(d) - names - {"kind"})
    if unknown:
        raise ConfigError(f"{where} ({kind}): unknown key(s) {unknown}; allowed: {sorted(names)}")
    if "id" not in d:
        raise ConfigError(f"{where} ({kind}): missing 'id'")
    kwargs = {k: _convert(v) for k, v in d.items() if k != "kind"}
    try:
        return cls(**kwargs)
    except TypeError as exc:
        raise ConfigError(f"{where} ({kind}): {exc}") from None
