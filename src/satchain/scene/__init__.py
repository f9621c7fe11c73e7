"""satchain.scene: synthetic ground truth rendered exactly at any pixel size, and real images as ground truth.

Axes: origin at the top-left corner of pixel [0, 0]; x (ACT) right along columns, y (ALT) down along rows;
pixel [i, j] covers x in [j p, (j+1) p), y in [i p, (i+1) p). Windows are (row0, col0, height, width).
See :mod:`satchain.scene.shapes` (exact coverage), :mod:`satchain.scene.layout` (scenes, files, truth),
:mod:`satchain.scene.materials` (the spectral material library) and :mod:`satchain.scene.spectral` (items named by
material; a scene as a band sees it).
"""

from satchain.scene.image import ImageScene
from satchain.scene.layout import (
    ITEM_KINDS,
    OBJECT_KINDS,
    TARGET_KINDS,
    Scene,
    layout_from_dict,
    layout_to_dict,
    load_layout,
    paper_layout,
)
from satchain.scene.materials import Material, band_reflectance, material, materials, vegetation
from satchain.scene.objects import Car, House, Railway, Road, Wagon
from satchain.scene.render import parse_cli_window, render_scene_to_file
from satchain.scene.shapes import polygon_coverage
from satchain.scene.spectral import MaterialSlot, layout_for_band
from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = [
    "ITEM_KINDS",
    "OBJECT_KINDS",
    "TARGET_KINDS",
    "BarTarget",
    "Car",
    "House",
    "HyperbolicWedge",
    "ImageScene",
    "Material",
    "MaterialSlot",
    "Railway",
    "Road",
    "Scene",
    "SiemensStar",
    "SlantedEdge",
    "Wagon",
    "band_reflectance",
    "layout_for_band",
    "layout_from_dict",
    "layout_to_dict",
    "load_layout",
    "material",
    "materials",
    "paper_layout",
    "parse_cli_window",
    "polygon_coverage",
    "render_scene_to_file",
    "vegetation",
]
