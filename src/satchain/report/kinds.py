"""The report layer's registry of target kinds: how each measurable scene kind is shown.

Each entry names the scene ``kind`` (the item class's ``kind`` constant), the ``key`` its measurements are
grouped under in ``measured``/``results.json`` (the measure layer owns it: :data:`satchain.measure._keys.RESULT_KEY`,
which :data:`satchain.measure.auto.MEASURERS` reads too), the words and colour the figures use, the region
overlay drawn on its thumbnails (:mod:`satchain.report.overlays`) and the figure ``satchain measure auto``
writes for it (:mod:`satchain.report.measure_plots`).  A new target kind is one entry here and one in the measure layer.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from satchain.measure._keys import RESULT_KEY
from satchain.report import overlays
from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = ["BARS", "EDGES", "REPORT_KINDS", "RESULT_KEYS", "STARS", "WEDGES", "ReportKind", "measured_entries"]


@dataclass(frozen=True)
class ReportKind:
    """How one target kind is shown (see the module docstring)."""

    kind: str
    key: str
    label: str
    colour: str
    overlay: Callable[[dict, dict, overlays.OverlayView], list[str]]
    plot_name: str

    def plot(self, result, path: str | Path, *, title: str = "", pixel_m: float | None = None) -> None:
        """The measurement's own figure (``satchain measure auto``), from its core result object."""
        from satchain.report import measure_plots  # matplotlib: imported only when a figure is drawn

        getattr(measure_plots, self.plot_name)(result, path, title=title, pixel_m=pixel_m)


def _entry(cls, label: str, colour: str, overlay, plot_name: str) -> ReportKind:
    return ReportKind(cls.kind, RESULT_KEY[cls.kind], label, colour, overlay, plot_name)


#: The registry, in the order the report lists the kinds.
REPORT_KINDS: dict[str, ReportKind] = {
    e.kind: e
    for e in (
        _entry(SlantedEdge, "slanted edge", "tab:red", overlays.edge_overlay, "plot_edge"),
        _entry(SiemensStar, "Siemens star", "tab:blue", overlays.star_overlay, "plot_star"),
        _entry(BarTarget, "bar target", "tab:orange", overlays.bars_overlay, "plot_bars"),
        _entry(HyperbolicWedge, "hyperbolic wedge", "tab:green", overlays.wedge_overlay, "plot_wedge"),
    )
}
#: The entries that code specific to one kind reads (its curves, its table rows).
EDGES, STARS, BARS, WEDGES = (REPORT_KINDS[c.kind] for c in (SlantedEdge, SiemensStar, BarTarget, HyperbolicWedge))
#: The keys of ``measured`` / ``results.json`` that hold per-target entries.
RESULT_KEYS: tuple[str, ...] = tuple(e.key for e in REPORT_KINDS.values())


def measured_entries(res: dict | None) -> Iterator[tuple[ReportKind, dict]]:
    """Every per-target entry of a ``measured`` or ``results.json`` dict, with its kind, in registry order."""
    for e in REPORT_KINDS.values():
        for x in (res or {}).get(e.key) or []:
            yield e, x
