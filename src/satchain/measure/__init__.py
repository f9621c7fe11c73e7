"""Image-quality measurement from images: slanted edge, Siemens star, bar targets, hyperbolic wedge, and the
line-of-sight motion (jitter) seen by a long straight edge.

Independent of the prediction path (``satchain.tf``, ``satchain.tf.ctf``): agreement between the two is the
project's check of correctness.

The names below are imported on first use (PEP 562), so that a module that needs one small part of the package
(the report's registry reads :mod:`satchain.measure._keys`) does not load every measurement and scipy.optimize.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

#: public name -> module it lives in (imported on first use).
_LAZY = {
    "Clipping": "satchain.measure._clipping",
    "find_clipping": "satchain.measure._clipping",
    "BarsResult": "satchain.measure.bars",
    "measure_bars": "satchain.measure.bars",
    "mtf_from_ctf_samples": "satchain.measure.bars",
    "EdgeResult": "satchain.measure.edge",
    "measure_edge": "satchain.measure.edge",
    "JitterResult": "satchain.measure.jitter",
    "measure_jitter": "satchain.measure.jitter",
    "StarResult": "satchain.measure.star",
    "measure_star": "satchain.measure.star",
    "WedgeResult": "satchain.measure.wedge",
    "measure_wedge": "satchain.measure.wedge",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'satchain.measure' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


if TYPE_CHECKING:  # for type checkers and IDEs: the lazy names, statically
    from satchain.measure._clipping import Clipping, find_clipping  # noqa: F401
    from satchain.measure.bars import BarsResult, measure_bars, mtf_from_ctf_samples  # noqa: F401
    from satchain.measure.edge import EdgeResult, measure_edge  # noqa: F401
    from satchain.measure.jitter import JitterResult, measure_jitter  # noqa: F401
    from satchain.measure.star import StarResult, measure_star  # noqa: F401
    from satchain.measure.wedge import WedgeResult, measure_wedge  # noqa: F401
