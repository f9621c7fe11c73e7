"""Scenes: a background plus placed items, the paper's default layout, scene files and the truth record.

A :class:`Scene` is the ground-truth interface the engine reads (shared with
:class:`~satchain.scene.image.ImageScene`)::

    scene.extent_m            -> (width_m, height_m)
    scene.pixel_m             -> default render pixel size (m)
    scene.shape_px(pixel_m)   -> (rows, cols) covering the extent
    scene.render(window, *, pixel_m) -> float32 reflectance, shape (height, width)

``window = (row0, col0, height, width)`` in pixels at ``pixel_m``. Every pixel is the exact area
average of the scene over its own footprint, so a window renders identically to the same crop of a
full render, and items whose bounding box misses the window are skipped (cost scales with the window).

Scene files (TOML or JSON)::

    [scene]
    width_m = 200.0
    height_m = 300.0
    background = 0.2      # reflectance
    pixel_m = 0.035       # default render pixel size

    [[items]]
    kind = "slanted_edge" # or bar_target, hyperbolic_wedge, siemens_star, road, car, railway, wagon, house
    id = "edge_act_5"
    center_m = [35.0, 35.0]
    angle_deg = 5.0

Items are painted in file order (painter's order). Keys are the item classes' fields. A grey reflectance may be
given as a material instead (``bright_material = "white_paint"``, ``[scene] background_material = "dry_grass"``, or
a ``.csv`` spectrum file): see :mod:`satchain.scene.spectral`.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from satchain._validate import check_positive
from satchain.errors import ConfigError, SatchainIOError
from satchain.scene.base import Item, check_reflectance, item_from_dict
from satchain.scene.objects import Car, House, Railway, Road, Wagon
from satchain.scene.shapes import Window, check_window
from satchain.scene.spectral import (
    MaterialSlot,
    apply_grey,
    materials_to_dicts,
    scene_grey,
    split_materials,
)
from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "ITEM_KINDS",
    "OBJECT_KINDS",
    "TARGET_KINDS",
    "Scene",
    "TRUTH_FORMAT",
    "check_scene_pixel",
    "layout_from_dict",
    "layout_to_dict",
    "load_layout",
    "paper_layout",
]

#: Test targets (an image-quality measurement is defined for each) and real-world objects (none), by kind.
TARGET_KINDS: tuple[str, ...] = tuple(c.kind for c in (SlantedEdge, BarTarget, HyperbolicWedge, SiemensStar))
OBJECT_KINDS: tuple[str, ...] = tuple(c.kind for c in (Road, Car, Railway, Wagon, House))
#: The scene layer's registry: every item kind a layout may name, to its class.
ITEM_KINDS: dict[str, type[Item]] = {
    cls.kind: cls for cls in (SlantedEdge, BarTarget, HyperbolicWedge, SiemensStar, Road, Car, Railway, Wagon, House)
}
TRUTH_FORMAT = "satchain-scene-truth/1"
CONVENTIONS = {
    "origin": "scene origin (x, y) = (0, 0) is the top-left corner of pixel [0, 0]",
    "x": "metres, across-track (ACT), increasing to the right along columns",
    "y": "metres, along-track (ALT), increasing downwards along rows",
    "pixel": "pixel [i, j] covers x in [j p, (j+1) p), y in [i p, (i+1) p) at pixel size p",
    "window_px": "(row0, col0, height, width) in pixels at pixel_m",
    "bbox_m": "[xmin, ymin, xmax, ymax] in metres",
    "bbox_px": "[row0, col0, height, width] of the pixels the bbox touches, at pixel_m, full-scene indices",
    "angles": "measured from +x towards +y (clockwise on screen) unless an item says otherwise",
}


@dataclasses.dataclass(frozen=True)
class Scene:
    """Background reflectance plus items painted in order, over ``[0, width_m] x [0, height_m]``.

    Examples
    --------
    >>> edge = SlantedEdge("e", center_m=(5.0, 2.0), size_m=2.0, angle_deg=0.0)
    >>> s = Scene(10.0, 4.0, (edge,), background=0.2)
    >>> s.shape_px(1.0)
    (4, 10)
    >>> s.render((1, 3, 2, 4), pixel_m=1.0).astype(float).round(3).tolist()
    [[0.2, 0.05, 0.8, 0.2], [0.2, 0.05, 0.8, 0.2]]
    """

    width_m: float
    height_m: float
    items: tuple[Item, ...] = ()
    background: float = 0.2
    pixel_m: float = 0.035
    name: str = "custom"
    #: materials filling grey slots (:mod:`satchain.scene.spectral`); the scene renders each as its mean over
    #: the default band, :func:`~satchain.scene.spectral.layout_for_band` as a band sees it
    materials: tuple[MaterialSlot, ...] = ()

    def __post_init__(self):
        check_positive("scene.width_m", self.width_m)
        check_positive("scene.height_m", self.height_m)
        check_reflectance("scene.background", self.background)
        check_positive("scene.pixel_m", self.pixel_m)
        object.__setattr__(self, "items", tuple(self.items))
        seen: set[str] = set()
        for it in self.items:
            if not isinstance(it, Item):
                raise ConfigError(f"scene.items: {it!r} is not a scene item")
            if it.id in seen:
                raise ConfigError(f"scene.items: duplicate id {it.id!r}; ids must be unique")
            seen.add(it.id)
        object.__setattr__(self, "materials", tuple(self.materials))
        if self.materials:
            for s in self.materials:
                if not isinstance(s, MaterialSlot):
                    raise ConfigError(f"scene.materials: {s!r} is not a MaterialSlot")
            items, background = apply_grey(self.items, self.background, self.materials, scene_grey)
            object.__setattr__(self, "items", items)
            object.__setattr__(self, "background", background)
        object.__setattr__(self, "_bboxes", tuple(it.bbox_m() for it in self.items))

    @property
    def extent_m(self) -> tuple[float, float]:
        """(width_m, height_m)."""
        return (self.width_m, self.height_m)

    def shape_px(self, pixel_m: float | None = None) -> tuple[int, int]:
        """(rows, cols) of pixels covering the extent at ``pixel_m`` (default: the scene's)."""
        p = self.pixel_m if pixel_m is None else check_positive("pixel_m", pixel_m)
        return (max(1, math.ceil(self.height_m / p - 1e-9)), max(1, math.ceil(self.width_m / p - 1e-9)))

    def render(self, window: Window | None = None, *, pixel_m: float | None = None) -> np.ndarray:
        """Reflectance of ``window`` (default: the whole scene) at ``pixel_m``, float32."""
        p = self.pixel_m if pixel_m is None else check_positive("pixel_m", pixel_m)
        window = (0, 0, *self.shape_px(p)) if window is None else check_window(window)
        row0, col0, h, w = window
        out = np.empty((h, w), dtype=np.float32)
        cuts = _row_bands(h, w)
        if len(cuts) == 2:
            self._paint_into(out, window, p)
            return out
        # a large window: row bands painted on threads (the heavy work is NumPy, which releases the GIL);
        # every pixel is its own area average, so a band is exactly those rows of the whole window
        from concurrent.futures import ThreadPoolExecutor

        bands = [(out[a:b], (row0 + a, col0, b - a, w)) for a, b in zip(cuts[:-1], cuts[1:], strict=False)]
        with ThreadPoolExecutor(_render_threads()) as pool:
            list(pool.map(lambda band: self._paint_into(band[0], band[1], p), bands))
        return out

    def _paint_into(self, out: np.ndarray, window: tuple[int, int, int, int], p: float) -> None:
        """Paint ``window`` (at pixel size ``p``) into ``out`` (float32, its shape)."""
        row0, col0, h, w = window
        image = np.full((h, w), float(self.background))
        x0, y0, x1, y1 = col0 * p, row0 * p, (col0 + w) * p, (row0 + h) * p
        for item, (bx0, by0, bx1, by1) in zip(self.items, self._bboxes, strict=True):  # type: ignore[attr-defined]
            if bx1 >= x0 - p and bx0 <= x1 + p and by1 >= y0 - p and by0 <= y1 + p:
                item.paint(image, window, p)
        out[...] = image

    def truth(self, pixel_m: float | None = None, window: Window | None = None) -> dict[str, Any]:
        """The truth record: conventions, extent and every item's kind, id, bbox and parameters."""
        p = self.pixel_m if pixel_m is None else check_positive("pixel_m", pixel_m)
        window = (0, 0, *self.shape_px(p)) if window is None else check_window(window)
        items = []
        for item, bbox in zip(self.items, self._bboxes, strict=True):  # type: ignore[attr-defined]
            t = item.truth()
            r0, c0 = math.floor(bbox[1] / p), math.floor(bbox[0] / p)
            t["bbox_px"] = [r0, c0, math.ceil(bbox[3] / p) - r0, math.ceil(bbox[2] / p) - c0]
            r, c, h, w = window
            t["in_window"] = bool(
                bbox[2] > c * p and bbox[0] < (c + w) * p and bbox[3] > r * p and bbox[1] < (r + h) * p
            )
            items.append(t)
        return _jsonable(
            {
                "format": TRUTH_FORMAT,
                "scene": self.name,
                "pixel_m": p,
                "extent_m": list(self.extent_m),
                "shape_px": list(self.shape_px(p)),
                "window_px": list(window),
                "background": self.background,
                "conventions": CONVENTIONS,
                "items": items,
                **({"materials": _materials_truth(self.materials)} if self.materials else {}),
            }
        )


#: Windows of at least this many pixels are painted in row bands on threads (smaller ones: not worth it).
PARALLEL_RENDER_PX = 1 << 21


#: An item whose smallest dimension spans fewer scene pixels than this is not resolved by its raster.
MIN_FEATURE_PX = 3.0

#: What the scene raster's pixel costs in the image of an object smaller than the GSD (issue 29, checked against
#: GalSim): the largest error, as a fraction of the object's peak, at scene pixels of GSD/7, GSD/14 and GSD/28.
RASTER_ERROR_NOTE = (
    "the raster is not band-limited: an object smaller than the GSD needs a scene pixel near GSD/28 for 1e-3 of "
    "its image's peak (GSD/14: 2.3e-3, GSD/7: 4.9e-3)"
)


def check_scene_pixel(scene: Scene, pixel_m: float, *, name: str = "pixel_m") -> list[str]:
    """Warn (:class:`~satchain.errors.SatchainWarning`) when an item's smallest dimension
    (:attr:`~satchain.scene.base.Item.smallest_feature_m`) spans fewer than :data:`MIN_FEATURE_PX` scene pixels
    at ``pixel_m``: its raster holds the area averages of its pixels, not its shape. Returns the ids warned of.

    Examples
    --------
    >>> check_scene_pixel(paper_layout(), 0.035)
    []
    """
    import warnings

    from satchain.errors import SatchainWarning

    fine = [(it, it.smallest_feature_m) for it in getattr(scene, "items", ())]
    fine = sorted(
        ((f, it) for it, f in fine if f is not None and f < MIN_FEATURE_PX * pixel_m * (1 - 1e-9)), key=lambda t: t[0]
    )
    if fine:
        shown = ", ".join(f"{it.id} ({it.kind}) {f:.3g} m = {f / pixel_m:.2g} px" for f, it in fine[:3])
        more = f" and {len(fine) - 3} more" if len(fine) > 3 else ""
        warnings.warn(
            f"{name} = {pixel_m:g} m: {len(fine)} scene item(s) have features narrower than {MIN_FEATURE_PX:g} scene "
            f"pixels ({shown}{more}), finer than the raster resolves; {RASTER_ERROR_NOTE}",
            SatchainWarning,
            stacklevel=2,
        )
    return [it.id for _, it in fine]


def _render_threads() -> int:
    """Threads for painting one window: the CPUs this process may use, at most 4."""
    import os

    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(4, cpus))


def _row_bands(h: int, w: int) -> list[int]:
    """Row cuts ``[0, ..., h]`` of a ``h x w`` window: one band below :data:`PARALLEL_RENDER_PX` or on one
    CPU, else four bands per thread (so that targets crowded into a few rows still spread), at least 64
    rows each."""
    threads = _render_threads()
    n = 1 if h * w < PARALLEL_RENDER_PX or threads == 1 else max(1, min(4 * threads, h // 64))
    return [h * i // n for i in range(n + 1)]


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _materials_truth(slots: tuple[MaterialSlot, ...]) -> list[dict[str, Any]]:
    return [
        {"item": s.item_id, "slot": s.slot, "material": s.material.name, "key": s.key, "source": s.material.source}
        for s in slots
    ]


def layout_from_dict(d: dict[str, Any], *, base_dir: str | os.PathLike | None = None) -> Scene:
    """Build a :class:`Scene` from ``{"scene": {...}, "items": [...]}`` (the scene-file structure); spectrum files
    named by ``*_material`` keys are relative to ``base_dir`` (default: the working directory)."""
    if not isinstance(d, dict) or "scene" not in d:
        raise ConfigError("layout: must have a [scene] table with width_m and height_m")
    base = None if base_dir is None else Path(base_dir)
    head, found = split_materials(dict(d["scene"]), "scene", None, base_dir=base)
    slots = [MaterialSlot(None, slot, m, key) for slot, m, key in found]
    allowed = {"width_m", "height_m", "background", "pixel_m", "name"}
    unknown = sorted(set(head) - allowed)
    if unknown:
        raise ConfigError(f"scene: unknown key(s) {unknown}; allowed: {sorted(allowed | {'background_material'})}")
    for key in ("width_m", "height_m"):
        if key not in head:
            raise ConfigError(f"scene.{key}: missing")
    items = []
    for i, it in enumerate(d.get("items", [])):
        kind = it.get("kind") if isinstance(it, dict) else None
        if isinstance(it, dict) and kind in ITEM_KINDS:
            it, found = split_materials(it, f"items[{i}] ({kind})", kind, base_dir=base)
        else:
            found = []
        item = item_from_dict(ITEM_KINDS, it, f"items[{i}]")
        slots += [MaterialSlot(item.id, slot, m, key) for slot, m, key in found]
        items.append(item)
    unknown_top = sorted(set(d) - {"scene", "items"})
    if unknown_top:
        raise ConfigError(f"layout: unknown top-level key(s) {unknown_top}; allowed: ['items', 'scene']")
    return Scene(items=tuple(items), materials=tuple(slots), **head)


def layout_to_dict(scene: Scene) -> dict[str, Any]:
    """Inverse of :func:`layout_from_dict` (JSON-serialisable)."""
    head = {
        "width_m": scene.width_m,
        "height_m": scene.height_m,
        "background": scene.background,
        "pixel_m": scene.pixel_m,
        "name": scene.name,
    }
    items = [{"kind": it.kind, **dataclasses.asdict(it)} for it in scene.items]
    if scene.materials:
        keys = materials_to_dicts(scene.materials)
        for target in [head, *items]:
            own = keys.get(None if target is head else target["id"], {})
            for k in own:
                slot = k[: -len("_material")]
                grey = ("mean", "amplitude") if target.get("kind") == "siemens_star" else (slot,)
                for g in grey:
                    target.pop(g, None)
            target.update(own)
    return _jsonable({"scene": head, "items": items})


def load_layout(source: str | os.PathLike) -> Scene:
    """``"paper"`` for :func:`paper_layout`, else a ``.toml`` or ``.json`` scene file."""
    if str(source) == "paper":
        return paper_layout()
    path = Path(source)
    if not path.is_file():
        what = "a folder, not a scene file (.toml or .json)" if path.is_dir() else "not 'paper' and no such file"
        raise SatchainIOError(f"layout = {str(source)!r}: {what}")
    try:
        text = path.read_text(encoding="utf-8")
        if path.suffix.lower() == ".toml":
            data = tomllib.loads(text)
        elif path.suffix.lower() == ".json":
            data = json.loads(text)
        else:
            raise ConfigError(f"layout = {str(path)!r}: file must end in .toml or .json")
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise ConfigError(f"layout = {str(path)!r}: cannot parse: {exc}") from None
    except UnicodeDecodeError as exc:
        from satchain._safety import not_utf8

        raise not_utf8(path, exc, "layout") from None
    except OSError as exc:
        raise SatchainIOError(f"layout = {str(path)!r}: cannot read: {exc}") from None
    return layout_from_dict(data, base_dir=path.parent)


def paper_layout() -> Scene:
    """The default scene, mirroring the reference paper's Figure 1 (portrait, 200 m x 300 m).

    Left column: slanted edges 60 m square (5 deg ACT, below it 5 deg ALT, then 10 deg ACT). Next:
    a vertical hyperbolic wedge, a 32-cycle sine Siemens star (radius 25 m), houses; middle band: a
    four-lane highway with sedans and station wagons, two railway tracks with boxcars and a tank car,
    a residential street with houses; bottom: parked cars (left), 3-bar targets in ACT and ALT rows and a
    horizontal hyperbolic wedge (bottom right). At 0.035 m pixels it is 5715 x 8572 pixels (49 Mpx).

    Examples
    --------
    >>> s = paper_layout()
    >>> s.extent_m, len(s.items) > 40
    ((200.0, 300.0), True)
    """
    items: list[Item] = [
        SlantedEdge("edge_act_5deg", center_m=(35.0, 35.0), angle_deg=5.0, measures="act"),
        SlantedEdge("edge_alt_5deg", center_m=(35.0, 105.0), angle_deg=5.0, measures="alt"),
        SlantedEdge("edge_act_10deg", center_m=(35.0, 175.0), angle_deg=10.0, measures="act"),
        HyperbolicWedge("wedge_vertical", origin_m=(72.0, 5.0), orientation="vertical"),
        SiemensStar("siemens_star", center_m=(122.0, 36.0), radius_m=25.0, cycles=32),
        House("house_1", origin_m=(176.0, 18.0)),
        House("house_2", origin_m=(176.0, 38.0), rotation_deg=90.0, length_m=12.2, width_m=9.1),
        House("house_3", origin_m=(176.0, 60.0)),
        Road("highway", origin_m=(70.0, 89.0), length_m=128.0),
    ]
    cars = [
        (80.0, 1.83, "sedan"),
        (101.0, 5.49, "station_wagon"),
        (125.0, 1.83, "station_wagon"),
        (150.0, 5.49, "sedan"),
        (92.0, -1.83, "sedan"),
        (118.0, -5.49, "sedan"),
        (140.0, -1.83, "station_wagon"),
        (170.0, -5.49, "station_wagon"),
    ]
    for k, (x, v, model) in enumerate(cars):
        items.append(Car(f"car_hw_{k}", origin_m=(x, 89.0 + v), rotation_deg=0.0 if v > 0 else 180.0, model=model))
    items += [
        Railway("railway_1", origin_m=(70.0, 109.0), length_m=128.0),
        Railway("railway_2", origin_m=(70.0, 113.5), length_m=128.0),
        Wagon("wagon_boxcar_1", origin_m=(88.0, 109.0), model="boxcar"),
        Wagon("wagon_tank_1", origin_m=(107.0, 109.0), model="tank"),
        Wagon("wagon_boxcar_2", origin_m=(126.5, 109.0), model="boxcar"),
        Wagon("wagon_tank_2", origin_m=(160.0, 113.5), model="tank"),
        Road(
            "street",
            origin_m=(100.0, 120.0),
            rotation_deg=90.0,
            length_m=85.0,
            lanes_per_direction=1,
            shoulder_m=0.0,
        ),
    ]
    for k, y in enumerate((133.0, 150.0, 167.0, 184.0)):
        items.append(House(f"house_w{k}", origin_m=(85.0, y), rotation_deg=90.0 * (k % 2)))
        items.append(House(f"house_e{k}", origin_m=(118.0, y), length_m=12.2, width_m=9.1))
        items.append(
            Car(
                f"car_drive_{k}",
                origin_m=(129.0, y + 2.0),
                rotation_deg=180.0,
                model=("sedan", "station_wagon")[k % 2],
            )
        )
    for k, y in enumerate((140.0, 165.0, 190.0)):
        items.append(House(f"house_x{k}", origin_m=(160.0, y), rotation_deg=15.0 * (k - 1)))
    for row, y in enumerate((225.0, 240.0, 255.0)):
        for k in range(8):
            items.append(
                Car(
                    f"car_lot_{row}_{k}",
                    origin_m=(10.0 + 2.8 * k, y),
                    rotation_deg=90.0,
                    model=("sedan", "station_wagon")[(k + row) % 2],
                    body=0.2 + 0.08 * k,
                )
            )
    items += [
        House("house_lot", origin_m=(55.0, 280.0)),
        BarTarget("bars_act", origin_m=(120.0, 214.0), orientation="act"),
        BarTarget("bars_alt", origin_m=(120.0, 234.0), orientation="alt"),
        HyperbolicWedge("wedge_horizontal", origin_m=(132.0, 270.0), orientation="horizontal"),
    ]
    return Scene(200.0, 300.0, tuple(items), background=0.2, pixel_m=0.035, name="paper")
