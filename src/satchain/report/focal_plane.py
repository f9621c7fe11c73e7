"""The report's "focal plane as flown" section: the bands, colour planes and staggered arrays a run formed
(:mod:`satchain.focal`), drawn from results.json's entries of those keys.

Each key's module (``focal_bands``, ``focal_cfa``, ``focal_staggered``) gives ``parts(data, fig_dir)``: the
section's words, tables and figures (drawn into ``fig_dir``) as :class:`FocalParts`; the template lays them out.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from satchain.report import focal_bands, focal_cfa, focal_staggered
from satchain.report.focal_parts import FocalParts, FocalTable

__all__ = ["REPORTERS", "FocalParts", "FocalTable", "focal_parts"]


#: results.json key -> its parts (``parts(data, fig_dir) -> FocalParts``)
REPORTERS: dict[str, Callable[[Mapping[str, Any], Path], FocalParts]] = {
    "bands": focal_bands.parts,
    "cfa": focal_cfa.parts,
    "staggered": focal_staggered.parts,
}


def focal_parts(results: Mapping[str, Any], fig_dir: Path) -> list[FocalParts]:
    """The parts of every focal-plane entry results.json holds, in :data:`REPORTERS`' order (none: [])."""
    fig_dir.mkdir(parents=True, exist_ok=True)
    return [fn(results[key], fig_dir) for key, fn in REPORTERS.items() if results.get(key)]
