"""(being built: issue 32) The staggered section of a run; see :mod:`satchain.focal`."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from satchain.config.run import RunConfig
    from satchain.results import BudgetResult, FocalSection, SceneResult

__all__ = ["section"]


def section(config: RunConfig, budget: BudgetResult, scene: SceneResult, progress) -> FocalSection | None:
    """None until built."""
    return None
