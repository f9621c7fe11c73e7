"""(being built: issue 32) The report's staggered part (:mod:`satchain.report.focal_plane`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from satchain.report.focal_parts import FocalParts

__all__ = ["parts"]


def parts(data: Mapping[str, Any], fig_dir: Path) -> FocalParts:
    """The staggered section's words, tables and figures (drawn into ``fig_dir``)."""
    return FocalParts("focal-staggered", str(data.get("title", "staggered")))
