"""The results key of each measurable scene kind (``measured`` / ``results.json``): the measure layer's names,
read by :data:`satchain.measure.auto.MEASURERS` and by the report's registry (:mod:`satchain.report.kinds`),
which thus needs none of the measurement code (a figure helper process imports the report alone)."""

from __future__ import annotations

from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = ["AT_NOISE_FLOOR", "RESULT_KEY"]

#: scene kind -> the key its results are grouped under, in the order of ``AutoResult.to_dict()``.
RESULT_KEY: dict[str, str] = {
    SlantedEdge.kind: "slanted_edges",
    SiemensStar.kind: "siemens_star",
    BarTarget.kind: "bar_targets",
    HyperbolicWedge.kind: "hyperbolic_wedge",
}

#: The flag of a bar group whose modulation is not above the noise (``group K: at_noise_floor: ...``, K its index in
#: the target's design): its CTF ~0, with its 1-sigma, is a result (a blur whose MTF vanishes there), not a refusal.
AT_NOISE_FLOOR = "at_noise_floor"
