"""Prediction: what the designed (or as-built) system should measure on each target of a run -- the edge response,
RER, NIIRS (:mod:`~satchain.prediction.quality`), the star's and wedge's limiting resolution
(:mod:`~satchain.prediction.star`, :mod:`~satchain.prediction.wedge`), the bars' modulation
(:mod:`~satchain.prediction.bars`), each formed as the same measurement on a noise-free image of the target
(:mod:`~satchain.prediction.target_image`) and on the image's own pushbroom geometry
(:mod:`~satchain.prediction.image_geometry`). :func:`predict` and :class:`Predictions` live in
:mod:`satchain.prediction.core` and are read from there on first use (PEP 562).
"""

from __future__ import annotations

import importlib
from typing import Any


def __getattr__(name: str) -> Any:
    if name.startswith("__"):
        raise AttributeError(name)
    return getattr(importlib.import_module("satchain.prediction.core"), name)
