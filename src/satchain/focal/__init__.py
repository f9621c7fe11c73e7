"""The focal plane as flown, in a run (issue 32): what ``satchain run`` forms, measures and compares beside its main
image when the system has more than one monochrome array.

- :mod:`satchain.focal.bands`: a ``[[bands]]`` system (PAN + MS): every band formed from the (spectral) scene,
  each band's edge MTF at its own Nyquist and SNR against its budget, and each band's offset from the PAN band
  (measured by :func:`satchain.measure.registration.measure_registration`) against the predicted one;
- :mod:`satchain.focal.cfa`: a ``[detector] cfa`` (Bayer) camera: the raw mosaic, each colour plane's MTF on its own
  grid against its prediction, and per demosaicing method the luminance MTF50 and the false colour at edges;
- :mod:`satchain.focal.staggered`: a staggered layout: the two arrays combined onto the half-pitch grid, its edges'
  MTF at the combined Nyquist and its bars above the single array's Nyquist against the prediction.

Each module's ``section(config, budget, scene, progress)`` returns a :class:`satchain.results.FocalSection` (or None
when the system has nothing of its kind): its check rows join the run's comparison, its ``data`` is results.json's
entry of its key, and the report draws its tables and figures from that entry (:mod:`satchain.report.focal_plane`).
A system with none of them runs exactly as before.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from satchain.focal import bands, cfa, staggered

if TYPE_CHECKING:
    from satchain.config.run import RunConfig
    from satchain.results import BudgetResult, FocalSection, SceneResult

__all__ = ["BUILDERS", "focal_sections"]

Progress = Callable[[str, int, int], None]

#: The section builders, in the order the run forms them and the report shows them.
BUILDERS = (bands.section, cfa.section, staggered.section)


def focal_sections(config: RunConfig, budget: BudgetResult, scene: SceneResult,
                   progress: Progress) -> tuple[FocalSection, ...]:  # fmt: skip
    """Every section the run's system has (none for a single monochrome array: the run is unchanged)."""
    out = []
    for build in BUILDERS:
        sec = build(config, budget, scene, progress)
        if sec is not None:
            out.append(sec)
    return tuple(out)
