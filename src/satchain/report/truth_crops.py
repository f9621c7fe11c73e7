"""The thumbnails' ground truth kept as the run's simulation renders the scene, so that the report does not
render those windows again (the exact Siemens star's is the longest render of a default run).

:class:`TruthCrops` stands in for the scene the simulation reads (:class:`satchain.engine.sources.SceneSource`
calls its ``render``): each window rendered at the run's ground pixel is passed on unchanged, and the part of it
that falls in a kept window is stored as grey levels (:func:`satchain.report.gallery.to_grey8`, pixel by pixel,
so a stored pixel is the one the report would make from its own render; every pixel is its own area average,
whatever the window). :meth:`TruthCrops.take` gives a panel's pixels once every one of them has been rendered;
a panel the simulation did not wholly render (its box reaches beyond the scene's pixels) is rendered by the
report as before.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from satchain.report.gallery import MAX_SIDE_PX, panel_window, to_grey8

__all__ = ["MAX_KEPT_PX", "TruthCrops"]

#: Most pixels kept in all (1 byte each, and 1 for the record of which are filled): larger windows are left
#: to the report to render.
MAX_KEPT_PX = 48_000_000


class TruthCrops:
    """``scene`` (anything with ``render(window, *, pixel_m)``), with the grey levels of ``boxes`` (m) at
    ``pixel_m`` kept as they are rendered; every other attribute is the scene's. A window larger than
    ``MAX_SIDE_PX`` on a side (its panel is block-averaged) or beyond :data:`MAX_KEPT_PX` in all is not kept."""

    def __init__(self, scene, boxes, pixel_m: float) -> None:
        self._scene, self._p = scene, float(pixel_m)
        self._kept: list[tuple[tuple[int, int, int, int], np.ndarray, np.ndarray]] = []
        total = 0
        for box in boxes:
            win = panel_window(box, self._p)
            h, w = win[2], win[3]
            if max(h, w) > MAX_SIDE_PX or total + h * w > MAX_KEPT_PX:
                continue
            total += h * w
            self._kept.append((win, np.zeros((h, w), np.uint8), np.zeros((h, w), bool)))

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name in ("_scene", "_p", "_kept"):
            raise AttributeError(name)
        return getattr(self._scene, name)

    def render(self, window=None, *, pixel_m: float | None = None) -> np.ndarray:
        out = self._scene.render(window, pixel_m=pixel_m)
        if window is None or pixel_m is None or float(pixel_m) != self._p:
            return out
        r0, c0, h, w = (int(v) for v in window)
        for (kr, kc, kh, kw), grey, seen in self._kept:
            a0, a1 = max(r0, kr), min(r0 + h, kr + kh)
            b0, b1 = max(c0, kc), min(c0 + w, kc + kw)
            if a0 < a1 and b0 < b1:
                grey[a0 - kr : a1 - kr, b0 - kc : b1 - kc] = to_grey8(out[a0 - r0 : a1 - r0, b0 - c0 : b1 - c0])
                seen[a0 - kr : a1 - kr, b0 - kc : b1 - kc] = True
        return out

    def take(self, box) -> np.ndarray | None:
        """The grey levels of the panel over ``box`` (m) if a kept window holds it, wholly rendered; else None."""
        r0, c0, h, w = panel_window(box, self._p)
        for (kr, kc, kh, kw), grey, seen in self._kept:
            if kr <= r0 and kc <= c0 and r0 + h <= kr + kh and c0 + w <= kc + kw:
                sub = (slice(r0 - kr, r0 - kr + h), slice(c0 - kc, c0 - kc + w))
                if seen[sub].all():
                    return grey[sub].copy()
        return None

    def release(self) -> None:
        """Free the kept pixels (after the panels were taken)."""
        self._kept = []
