"""The results key of each measurable scene kind (``measured`` / ``results.json``): the measure layer's names,
read by :data:`satchain.measure.auto.MEASURERS` and by the report's registry (:mod:`satchain.report.kinds`),
which thus needs none of the measurement code (a figure helper process imports the report alone)."""

from __future__ import annotations

from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = ["RESULT_KEY"]

#: scene kind -> the key its results are grouped under, in the order of ``AutoResult.to_dict()``.
RESULT_KEY: dict[str, str] = {
    SlantedEdge.kind: "slanted_edges",
    SiemensStar.kind: "siemens_star",
    BarTarget.kind: "bar_targets",
    HyperbolicWedge.kind: "hyperbolic_wedge",
}
