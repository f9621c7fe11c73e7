"""Region overlays drawn over the report's target thumbnails, as SVG in scene metres.

A thumbnail shows the box ``(x0, y0, x1, y1)`` (m) of its target; the overlay is an ``<svg>`` with that box as
its ``viewBox``, laid exactly over the image, so one overlay serves the ground-truth, focal-plane and detector
panels and scales with the click-to-zoom. What is drawn, per kind:

* slanted edge: the measured region and the fitted edge line (measured angle, through the truth's edge point);
* Siemens star: the measured annulus (inner and outer radius) and the Nyquist radius ``r = cycles GSD / pi``
  (the local period ``2 pi r / cycles`` is 2 GSD there);
* bar target: each group's box labelled with its period and whether it is compared (``f <= cut-off``),
  measured but not compared, or not measured;
* hyperbolic wedge: the scan line (the middle of the stripes, from the wide end) and the line width where the
  measured contrast crossed the threshold.

Under a pushbroom image geometry (Earth rotation's shear, an along-track scale, a yaw: ``to_image``, the run's
:meth:`~satchain.tf.pushbroom.PushbroomTerms.image_affine` from truth metres to image pixels) a panel need not
show the ground as the truth has it: each panel has its own map ``panel`` from truth metres to its coordinates
(:func:`satchain.report.gallery.panel_maps`: the detector's is the image's pixels, pixel ``(col, row)`` spanning
``[col, col + 1] x gsd``; under a yaw the focal plane's is the turned ground; None: truth metres). Every ground
feature goes through it (a box becomes a parallelogram, a circle an ellipse) and every measured region (image
pixels) back through ``to_image`` and then through it. The fitted edge is drawn through the measured per-line
edge positions (the measurement's own polynomial), so it lies on the edge as imaged in every panel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from html import escape

__all__ = [
    "OverlayView",
    "bars_overlay",
    "edge_line_points",
    "edge_overlay",
    "star_overlay",
    "wedge_overlay",
]

_LINE = 'vector-effect="non-scaling-stroke" fill="none"'
_COMPARED, _NOT_COMPARED, _NOT_MEASURED = "#ff8c00", "#3fa0ff", "#c0c0c0"
#: Width of an average character in ems (sans-serif), to fit a label into a box.
_CHAR_EM = 0.6


@dataclass(frozen=True)
class OverlayView:
    """How an overlay is drawn: the image's ground pixel and top-left corner (m), the text size (m), the
    highest bar-group frequency compared with the prediction (cy/px), the image map ``to_image`` (truth metres
    -> image ``(col, row)``, pixel centres at integers, as ``(a, b, c, d, e, f)``; None: the plain grid) and the
    ``panel``'s map from truth metres to its coordinates (6 numbers; None: truth metres; the module docstring)."""

    gsd_m: float
    origin_m: tuple[float, float]
    size: float
    compared_up_to_cy_per_px: float = 0.4
    to_image: tuple | None = None
    panel: tuple | None = None

    @property
    def mapped(self) -> bool:
        """Whether the panel is not the truth's metres (ground boxes are drawn as polygons)."""
        return self.panel is not None

    def ground(self, x: float, y: float) -> tuple[float, float]:
        """A truth point (m) in this panel's coordinates."""
        if self.panel is None:
            return float(x), float(y)
        a, b, c, d, e, f = self.panel
        return a * x + b * y + c, d * x + e * y + f

    def pixel(self, u: float, v: float) -> tuple[float, float]:
        """An image point in pixel-edge coordinates (pixel ``k`` spans ``[k, k + 1]``) in this panel's
        coordinates."""
        if self.to_image is None:
            return self.ground(self.origin_m[0] + u * self.gsd_m, self.origin_m[1] + v * self.gsd_m)
        a, b, c, d, e, f = self.to_image
        det = a * e - b * d
        du, dv = u - 0.5 - c, v - 0.5 - f
        return self.ground((e * du - b * dv) / det, (a * dv - d * du) / det)


def _text(x: float, y: float, s: str, size: float, colour: str, anchor: str = "start", rotate: bool = False) -> str:
    rot = f' transform="rotate(90 {x:.3f} {y:.3f})"' if rotate else ""
    return (
        f'<text x="{x:.3f}" y="{y:.3f}" font-size="{size:.3f}" fill="{colour}" text-anchor="{anchor}" '
        f'stroke="#000" stroke-width="{size / 8:.3f}" stroke-opacity="0.6" paint-order="stroke"{rot}>{escape(s)}</text>'
    )


def _rect(b, colour: str, dash: str = "") -> str:
    x0, y0, x1, y1 = b
    d = f' stroke-dasharray="{dash}"' if dash else ""
    return (
        f'<rect x="{x0:.3f}" y="{y0:.3f}" width="{x1 - x0:.3f}" height="{y1 - y0:.3f}" stroke="{colour}" '
        f'stroke-width="1.5" {_LINE}{d}/>'
    )


def _roi_m(m: dict, gsd: float, origin) -> tuple[float, float, float, float] | None:
    r = m.get("roi_px")
    if not r:
        return None
    ox, oy = origin
    return ox + r[0] * gsd, oy + r[1] * gsd, ox + r[2] * gsd, oy + r[3] * gsd


def _polygon(pts, colour: str, dash: str = "", closed: bool = True) -> str:
    d = f' stroke-dasharray="{dash}"' if dash else ""
    tag = "polygon" if closed else "polyline"
    xy = " ".join(f"{x:.3f},{y:.3f}" for x, y in pts)
    return f'<{tag} points="{xy}" stroke="{colour}" stroke-width="1.5" {_LINE}{d}/>'


def _corners(box) -> list[tuple[float, float]]:
    x0, y0, x1, y1 = box
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def _extent(pts) -> tuple[float, float, float, float]:
    xs, ys = [p[0] for p in pts], [p[1] for p in pts]
    return min(xs), min(ys), max(xs), max(ys)


def _pixel_box(v: OverlayView, roi, colour: str, dash: str = "") -> tuple[str, tuple]:
    """A measured region (pixel box ``(x0, y0, x1, y1)``, half-open) in the panel: its shape and extent."""
    pts = [v.pixel(u, w) for u, w in _corners(roi)]
    box = _extent(pts)
    straight = v.to_image is None or _is_image_frame(v)
    return (_rect(box, colour, dash) if straight else _polygon(pts, colour, dash)), box


def _is_image_frame(v: OverlayView) -> bool:
    """Whether the panel is the image's own pixel grid (its regions are rectangles there)."""
    if v.panel is None or v.to_image is None:
        return v.panel is None and v.to_image is None
    p0, p1, p2 = v.pixel(0.0, 0.0), v.pixel(1.0, 0.0), v.pixel(0.0, 1.0)
    return abs(p1[1] - p0[1]) < 1e-9 * v.gsd_m and abs(p2[0] - p0[0]) < 1e-9 * v.gsd_m


def _ground_box(v: OverlayView, bbox_m, colour: str, dash: str = "") -> tuple[str, tuple]:
    """A ground box (m) in the panel: its shape (a parallelogram in a mapped image's frame) and extent."""
    pts = [v.ground(x, y) for x, y in _corners(bbox_m)]
    box = _extent(pts)
    return (_polygon(pts, colour, dash) if v.mapped else _rect(box, colour, dash)), box


def edge_overlay(it: dict, m: dict, v: OverlayView) -> list[str]:
    """Slanted edge: the measured region and the fitted edge line."""
    size = v.size
    out = []
    roi = None
    if m.get("roi_px"):
        shape, roi = _pixel_box(v, m["roi_px"], "#ff4040")
        out.append(shape)
    a = m.get("angle_deg")
    pts = edge_line_points(it, m, v)
    if a is None or not pts:
        return out
    out.append(_polygon(pts, "#ffe000", closed=False))
    x0, y0 = (roi[0], roi[1]) if roi else _ground_box(v, it["bbox_m"], "")[1][:2]
    out.append(_text(x0 + 0.5 * size, y0 + 1.3 * size, f"edge fit {float(a):.3f}°", size, "#ffe000"))
    return out


def edge_line_points(it: dict, m: dict, v: OverlayView, n: int = 24) -> list[tuple[float, float]]:
    """The fitted edge in the panel: the measurement's polynomial (``fit_degree``) through its per-line edge
    positions over the lines it measured; without them, the measured angle through the truth's edge point."""
    import numpy as np

    lines, pos = m.get("lines"), m.get("edge_position_px")
    if lines and pos and len(lines) == len(pos):
        x = np.asarray(lines, float)
        y = np.asarray([np.nan if p is None else p for p in pos], float)
        ok = np.isfinite(y)
        deg = int(min(max(int(m.get("fit_degree") or 1), 1), 3))
        if np.count_nonzero(ok) > deg + 1:
            x, y = x[ok], y[ok]
            t = np.linspace(x.min(), x.max(), n)
            c = np.polyval(np.polyfit(x - x.mean(), y, deg), t - x.mean())
            act = str(m.get("direction") or it.get("measures")).upper() == "ACT"
            return [v.pixel(p + 0.5, q + 0.5) if act else v.pixel(q + 0.5, p + 0.5) for q, p in zip(t, c, strict=True)]
    a = m.get("angle_deg")
    if a is None or "edge_point_m" not in it:
        return []
    rad = math.radians(float(a))
    d = (math.sin(rad), math.cos(rad)) if str(it.get("measures")).lower() == "act" else (math.cos(rad), math.sin(rad))
    cx, cy = it["edge_point_m"]
    half = 0.5 * float(it.get("size_m", 10.0))
    return [v.ground(cx - half * d[0], cy - half * d[1]), v.ground(cx + half * d[0], cy + half * d[1])]


def _circle(cx: float, cy: float, r: float, colour: str, dash: str = "") -> str:
    d = f' stroke-dasharray="{dash}"' if dash else ""
    return f'<circle cx="{cx:.3f}" cy="{cy:.3f}" r="{r:.3f}" stroke="{colour}" stroke-width="1.5" {_LINE}{d}/>'


def star_overlay(it: dict, m: dict, v: OverlayView) -> list[str]:
    """Siemens star: the measured annulus and the Nyquist radius."""
    gsd, size = v.gsd_m, v.size
    if v.mapped or v.to_image is not None:
        return _star_mapped(it, m, v)
    cx, cy = it["center_m"]
    out = []
    radii = m.get("radius_px")
    if radii:
        for r in radii:
            out.append(_circle(cx, cy, float(r) * gsd, "#40c0ff"))
        out.append(_text(cx, cy - float(radii[1]) * gsd + 1.3 * size, "measured annulus", size, "#40c0ff", "middle"))
    r_nyq = float(it["cycles"]) * gsd / math.pi
    out.append(_circle(cx, cy, r_nyq, "#ff4040", "4 3"))
    out.append(_text(cx + r_nyq + 0.3 * size, cy, f"Nyquist (r = {r_nyq:.1f} m)", size, "#ff4040"))
    return out


def _star_mapped(it: dict, m: dict, v: OverlayView) -> list[str]:
    """:func:`star_overlay` under an image map: the annulus is a pair of circles in the image (pixels, about the
    measured centre), the Nyquist radius a circle on the ground; each an ellipse in the other frame."""
    size, k = v.size, 72
    ring = [(math.cos(2 * math.pi * j / k), math.sin(2 * math.pi * j / k)) for j in range(k)]
    cx, cy = it["center_m"]
    out = []
    radii, centre = m.get("radius_px"), m.get("center_xy_px")
    if radii and centre:
        u, w = float(centre[0]) + 0.5, float(centre[1]) + 0.5
        for r in radii:
            out.append(_polygon([v.pixel(u + float(r) * c, w + float(r) * s) for c, s in ring], "#40c0ff"))
        tx, ty = v.pixel(u, w - float(radii[1]))
        out.append(_text(tx, ty + 1.3 * size, "measured annulus", size, "#40c0ff", "middle"))
    r_nyq = float(it["cycles"]) * v.gsd_m / math.pi
    out.append(_polygon([v.ground(cx + r_nyq * c, cy + r_nyq * s) for c, s in ring], "#ff4040", "4 3"))
    tx, ty = v.ground(cx + r_nyq, cy)
    out.append(_text(tx + 0.3 * size, ty, f"Nyquist (r = {r_nyq:.1f} m)", size, "#ff4040"))
    return out


def bars_overlay(it: dict, m: dict, v: OverlayView) -> list[str]:
    """Bar target: each group's box with its period and whether it is compared, measured or not."""
    gsd, lim, size = v.gsd_m, v.compared_up_to_cy_per_px, v.size
    measured = {round(float(g.get("period_m", 0)), 9): g.get("period_px") for g in (m.get("groups") or [])}
    out = []
    for g in it.get("groups", []):
        period = float(g["period_m"])
        f = 1.0 / float(measured.get(round(period, 9)) or period / gsd)  # on the image's axis (its ground step)
        if round(period, 9) not in measured:
            colour, word = _NOT_MEASURED, "not measured"
        elif f <= lim + 1e-12:
            colour, word = _COMPARED, "compared"
        else:
            colour, word = _NOT_COMPARED, "not compared"
        shape, (x0, y0, x1, y1) = _ground_box(v, g["bbox_m"], colour, "" if word == "compared" else "3 2")
        out.append(shape)
        p_text = f"{period * 100:.0f} cm" if period < 1 else f"{period:g} m"
        p_size = min(size, (x1 - x0) / (_CHAR_EM * len(p_text)))  # shrunk to fit the group's width
        out.append(_text(0.5 * (x0 + x1), y0 + 1.1 * p_size, p_text, p_size, colour, "middle"))
        w_size = min(0.8 * size, (x1 - x0) / (_CHAR_EM * len(word)))
        out.append(_text(0.5 * (x0 + x1), y1 - 0.4 * w_size, word, w_size, colour, "middle"))
    return out


def wedge_overlay(it: dict, m: dict, v: OverlayView) -> list[str]:
    """Hyperbolic wedge: the scan along s at the middle of the stripes, and the measured resolution as a cross
    line."""
    size = v.size
    ox, oy = it["local_origin_m"]
    w0, x0, n, length = (float(it[k]) for k in ("line_width_start_m", "x0_m", "n_stripes", "length_m"))
    orient = str(it.get("orientation")).lower()
    if orient not in ("horizontal", "vertical"):
        return []

    def xy(s: float, t: float) -> tuple[float, float]:
        return v.ground(ox + s, oy + t) if orient == "horizontal" else v.ground(ox + t, oy + s)

    pts = []
    for k in range(41):
        s = length * k / 40
        w = w0 * x0 / (x0 + s)
        pts.append(xy(s, (n - 0.5) * w))
    out = [
        '<polyline points="{}" stroke="#40ff40" stroke-width="1.5" {}/>'.format(
            " ".join(f"{x:.3f},{y:.3f}" for x, y in pts), _LINE
        )
    ]
    rot = orient == "vertical"
    out.append(_text(*xy(0.6 * length, 0.55 * (2 * n) * w0), "scan, wide end first", size, "#40ff40", rotate=rot))
    res = m.get("resolution_m")
    if res:
        s = w0 * x0 / float(res) - x0
        w = float(res)
        (ax, ay), (bx, by) = xy(s, 0.0), xy(s, (2 * n) * w + 0.5 * size)
        out.append(f'<line x1="{ax:.3f}" y1="{ay:.3f}" x2="{bx:.3f}" y2="{by:.3f}" stroke="#ff4040" '
                   f'stroke-width="2" {_LINE}/>')  # fmt: skip
        label = f"{100 * float(m.get('threshold') or 0.15):.0f} % at {res * 100:.1f} cm"
        out.append(_text(*xy(s, (2 * n) * w + 1.6 * size), label, size, "#ff4040", rotate=rot))
    return out
