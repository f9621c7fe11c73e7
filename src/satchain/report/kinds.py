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

__all__ = [
    "BARS",
    "EDGES",
    "REPORT_KINDS",
    "RESULT_KEYS",
    "STARS",
    "WEDGES",
    "ReportKind",
    "measured_entries",
    "overlay_svg",
]


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


def overlay_svg(it: dict, measured: dict | None, box_m, *, gsd_m: float, origin_m=(0.0, 0.0),
                compared_up_to_cy_per_px: float = 0.4, display_px: float = 360.0, to_image=None,
                panel=None) -> str:  # fmt: skip
    """The overlay of truth item ``it`` (with its measurement ``measured``, or None) over a thumbnail of
    ``box_m`` (in the panel's coordinates), as an ``<svg>`` element string ('' for kinds without one). Text is
    about 12 CSS px when the thumbnail is shown ``display_px`` wide. ``to_image`` (the image map, truth metres ->
    pixels) and ``panel`` (truth metres -> the panel's coordinates), each an ``affine.Affine`` or 6 numbers: see
    the module docstring."""
    x0, y0, x1, y1 = (float(v) for v in box_m)
    size = 12.0 * (x1 - x0) / max(display_px, 1.0)
    entry = REPORT_KINDS.get(str(it.get("kind")))
    if entry is None:
        return ""
    geo, pan = (None if m is None else tuple(float(c) for c in tuple(m)[:6]) for m in (to_image, panel))
    view = overlays.OverlayView(float(gsd_m), tuple(origin_m), size, float(compared_up_to_cy_per_px), geo, pan)
    body = entry.overlay(it, measured or {}, view)
    return (
        f'<svg class="ov" viewBox="{x0:.3f} {y0:.3f} {x1 - x0:.3f} {y1 - y0:.3f}" preserveAspectRatio="none" '
        f'xmlns="http://www.w3.org/2000/svg" aria-hidden="true">{"".join(body)}</svg>'
    )
