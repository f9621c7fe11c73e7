"""Spectral scenes: scene items (and the background) that name a material instead of a grey reflectance.

Every grey reflectance *slot* of an item kind (:data:`MATERIAL_SLOTS`) may be given in a scene file as
``<slot>_material``, a name from the material library (:func:`satchain.scene.materials.materials`) or the path of a
CSV spectrum file (ending in ``.csv``, relative to the scene file; see
:func:`satchain.scene.materials.read_spectrum`); the background as ``[scene] background_material``. A slot takes a
grey value or a material, not both. A Siemens star takes ``bright_material`` and ``dark_material`` together (its
``mean`` and ``amplitude`` follow from them).

A scene keeps its materials (:class:`MaterialSlot`) and renders each as its mean over
:data:`~satchain.scene.materials.DEFAULT_BAND_M`; :func:`layout_for_band` gives the grey scene a band sees (every
material replaced by its band-integrated reflectance), which the renderer renders unchanged. A scene without
materials is its own band layout, for every band.

Example scene file::

    [scene]
    width_m = 100.0
    height_m = 100.0
    background_material = "dry_grass"

    [[items]]
    kind = "slanted_edge"
    id = "edge"
    center_m = [50.0, 50.0]
    bright_material = "white_paint"
    dark_material = "black_paint"
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from satchain.errors import ConfigError
from satchain.scene.base import Item
from satchain.scene.materials import (
    DEFAULT_BAND_M,
    Material,
    band_reflectance,
    default_grey,
    material,
    materials,
    read_spectrum,
)
from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = [
    "MATERIAL_SLOTS",
    "MaterialSlot",
    "apply_grey",
    "layout_for_band",
    "materials_to_dicts",
    "split_materials",
]

#: The grey reflectance slots of each item kind that a material may fill (``<slot>_material`` in a scene file).
#: A Siemens star's ``bright`` and ``dark`` are ``mean +- amplitude``.
MATERIAL_SLOTS: dict[str, tuple[str, ...]] = {
    SlantedEdge.kind: ("bright", "dark"),
    BarTarget.kind: ("bright", "dark"),
    HyperbolicWedge.kind: ("bright", "dark"),
    SiemensStar.kind: ("bright", "dark"),
    "road": ("asphalt", "shoulder", "white", "yellow"),
    "car": ("body", "glass", "wiper"),
    "railway": ("ballast", "tie", "rail"),
    "wagon": ("body", "detail"),
    "house": ("roof_lit", "roof_shaded", "ridge"),
}
SUFFIX = "_material"
_STAR = SiemensStar.kind


@dataclasses.dataclass(frozen=True)
class MaterialSlot:
    """A material filling one grey slot: ``item_id`` (None: the scene's background), ``slot`` (the grey field),
    the :class:`~satchain.scene.materials.Material`, and ``key``, as a scene file names it (a library name or a
    spectrum file's path; default: the material's name)."""

    item_id: str | None
    slot: str
    material: Material
    key: str = ""

    def __post_init__(self):
        if not isinstance(self.material, Material):
            raise ConfigError(f"material slot {self.slot!r}: {self.material!r} is not a Material")
        if not self.key:
            object.__setattr__(self, "key", self.material.name)


def _resolve(value: Any, where: str, base_dir: Path | None) -> Material:
    if not isinstance(value, str) or not value:
        raise ConfigError(f"{where} = {value!r}: must be a material name or a .csv spectrum file")
    if value.lower().endswith(".csv"):
        p = Path(value)
        if not p.is_absolute() and base_dir is not None:
            p = base_dir / p
        return read_spectrum(p, name=value)
    if value not in materials():
        raise ConfigError(f"{where} = {value!r}: not in the material library; known: {', '.join(materials())}")
    return material(value)


def split_materials(
    d: dict[str, Any], where: str, kind: str | None, *, base_dir: Path | None = None
) -> tuple[dict[str, Any], list[tuple[str, Material, str]]]:
    """Take the ``<slot>_material`` keys out of an item's (or, ``kind=None``, the ``[scene]`` table's) dict: the
    dict without them and ``[(slot, material, key)]``. Unknown slots, unknown materials and a slot given both a
    grey value and a material are ConfigErrors."""
    slots = ("background",) if kind is None else MATERIAL_SLOTS.get(kind, ())
    rest = {k: v for k, v in d.items() if not (isinstance(k, str) and k.endswith(SUFFIX))}
    found = []
    for k in sorted(set(d) - set(rest)):
        slot = k[: -len(SUFFIX)]
        if slot not in slots:
            allowed = ", ".join(s + SUFFIX for s in slots) or "none"
            raise ConfigError(f"{where}: unknown key {k!r}; material keys allowed here: {allowed}")
        if slot in d:
            raise ConfigError(f"{where}: {slot} = {d[slot]!r} and {k} = {d[k]!r}: give one, not both")
        if kind == _STAR and {"mean", "amplitude"} & set(d):
            raise ConfigError(f"{where}: a siemens_star with {k} takes no mean or amplitude (they follow)")
        found.append((slot, _resolve(d[k], f"{where}.{k}", base_dir), str(d[k])))
    if kind == _STAR and found and len(found) != 2:
        raise ConfigError(f"{where}: a siemens_star takes bright_material and dark_material together")
    return rest, found


def _star_values(item: SiemensStar, values: dict[str, float], where: str) -> dict[str, float]:
    mean, amp = float(item.mean), float(item.amplitude)
    bright, dark = values.get("bright", mean + amp), values.get("dark", mean - amp)
    if bright < dark:
        raise ConfigError(f"{where}: bright reflectance {bright:.4g} < dark {dark:.4g}; the star needs bright >= dark")
    return {"mean": (bright + dark) / 2, "amplitude": (bright - dark) / 2}


def apply_grey(
    items: tuple[Item, ...], background: float, slots: tuple[MaterialSlot, ...], grey
) -> tuple[tuple[Item, ...], float]:
    """``(items, background)`` with every slot set to ``grey(material)`` (a reflectance)."""
    by_id: dict[str | None, dict[str, float]] = {}
    for s in slots:
        by_id.setdefault(s.item_id, {})[s.slot] = grey(s.material)
    ids = {it.id for it in items}
    missing = sorted(str(i) for i in set(by_id) - ids - {None})
    if missing:
        raise ConfigError(f"scene.materials: no item with id {missing}")
    if None in by_id:
        extra = sorted(set(by_id[None]) - {"background"})
        if extra:
            raise ConfigError(f"scene.materials: the background has one slot, 'background'; got {extra}")
        background = by_id[None]["background"]
    out = []
    for it in items:
        values = by_id.get(it.id)
        if values:
            allowed = MATERIAL_SLOTS.get(it.kind, ())
            bad = sorted(set(values) - set(allowed))
            if bad:
                raise ConfigError(f"scene.materials: {it.kind} {it.id!r} has no slot {bad}; slots: {list(allowed)}")
            fields: dict[str, Any] = (
                _star_values(it, values, f"{it.kind} {it.id!r}") if isinstance(it, SiemensStar) else dict(values)
            )
            it = dataclasses.replace(it, **fields)
        out.append(it)
    return tuple(out), background


def scene_grey(m: Material) -> float:
    """A material's grey value in a scene rendered without a band (flat over DEFAULT_BAND_M)."""
    try:
        return default_grey(m)
    except ConfigError as exc:
        lo, hi = DEFAULT_BAND_M
        raise ConfigError(
            f"material {m.name!r}: a scene renders it over {lo * 1e9:.0f}-{hi * 1e9:.0f} nm without a band; {exc}"
        ) from None


def layout_for_band(layout, wavelengths_m, response):
    """The grey scene a band sees: every material of ``layout`` replaced by its band-integrated reflectance
    (:func:`~satchain.scene.materials.band_reflectance` of ``response`` sampled at ``wavelengths_m``); the result
    holds no materials and renders with the unchanged renderer. A layout without materials (or an image scene) is
    returned as it is.

    Examples
    --------
    >>> import numpy as np
    >>> from satchain.scene.layout import layout_from_dict
    >>> s = layout_from_dict({"scene": {"width_m": 10.0, "height_m": 10.0, "background_material": "water"}})
    >>> lam = np.linspace(800e-9, 900e-9, 11)
    >>> b = layout_for_band(s, lam, np.ones_like(lam))
    >>> b.materials, b.background < 0.1
    ((), True)
    """
    slots = getattr(layout, "materials", ())
    if not slots:
        return layout
    items, background = apply_grey(
        layout.items, layout.background, slots, lambda m: band_reflectance(m, wavelengths_m, response)
    )
    return dataclasses.replace(layout, items=items, background=background, materials=())


def materials_to_dicts(slots: tuple[MaterialSlot, ...]) -> dict[str | None, dict[str, str]]:
    """``{item_id (None: background): {"<slot>_material": key}}`` for writing a scene file."""
    out: dict[str | None, dict[str, str]] = {}
    for s in slots:
        out.setdefault(s.item_id, {})[s.slot + SUFFIX] = s.key
    return out
