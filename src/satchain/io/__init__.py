"""Image files and run folders: image reading and atomic writing (:mod:`~satchain.io.images`: tiled (Big)TIFF, PNG,
NPY), any raster GDAL reads by window (:mod:`~satchain.io.raster`), what a file says about its pixel size
(:mod:`~satchain.io.imagemeta`), outputs committed together (:mod:`~satchain.io._commit`) and a run folder's
manifest (:mod:`~satchain.io.runfolder`).

The names of the former ``satchain/io.py`` module (``satchain.io.write_tiff``, ``read_image``, ``atomic_path``, ...)
are read from :mod:`satchain.io.images` on first use (PEP 562).
"""

from __future__ import annotations

import importlib
from typing import Any


def __getattr__(name: str) -> Any:
    if name.startswith("__"):
        raise AttributeError(name)
    return getattr(importlib.import_module("satchain.io.images"), name)
