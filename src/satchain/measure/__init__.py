"""Image-quality measurement from images: slanted edge, Siemens star, bar targets, hyperbolic wedge, and the
line-of-sight motion (jitter) seen by a long straight edge.

Independent of the prediction path (``satchain.tf``, ``satchain.ctf``): agreement between the two is the
project's check of correctness.
"""

from satchain.measure._clipping import Clipping, find_clipping
from satchain.measure.bars import BarsResult, measure_bars, mtf_from_ctf_samples
from satchain.measure.edge import EdgeResult, measure_edge
from satchain.measure.jitter import JitterResult, measure_jitter
from satchain.measure.star import StarResult, measure_star
from satchain.measure.wedge import WedgeResult, measure_wedge

__all__ = [
    "BarsResult",
    "Clipping",
    "EdgeResult",
    "JitterResult",
    "StarResult",
    "WedgeResult",
    "find_clipping",
    "measure_bars",
    "measure_edge",
    "measure_jitter",
    "measure_star",
    "measure_wedge",
    "mtf_from_ctf_samples",
]
