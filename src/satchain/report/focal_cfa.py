"""The report's colour filter array part (:mod:`satchain.report.focal_plane`), drawn from results.json's ``cfa``
entry (:mod:`satchain.focal.cfa`) alone: the colour planes' table (each raw plane's MTF on its own grid, measured
against predicted), the demosaicing methods side by side (luminance MTF50, false colour), a figure of each
plane's MTF along the edge normal measured and predicted with its Nyquist and alias frequency marked, and a crop
of the reference edge as each method demosaiced it. matplotlib's object API only (no pyplot)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from satchain.report._save import save_figure
from satchain.report._style import axis_band_in, place_grid, title_band_in
from satchain.report.compare_plots import rc_for
from satchain.report.focal_parts import FocalParts, FocalTable

__all__ = ["parts", "plot_crops", "plot_plane_mtf"]

_COLOURS = ("red", "green", "blue")
_LINE = {"red": "tab:red", "green": "tab:green", "blue": "tab:blue"}
MTF_FIGURE = "cfa_plane_mtf.png"
CROPS_FIGURE = "cfa_demosaic_crops.png"


def _f(v: Any, digits: int = 4) -> str:
    return "–" if v is None else f"{float(v):.{digits}f}"


def _plane_table(data: Mapping[str, Any]) -> FocalTable:
    rows = []
    for e in data.get("edges", ()):
        if e.get("reason"):
            rows.append((e["id"], "all", "–", "–", "–", "–", "–", "–", "–", "–", f"n/a: {e['reason']}"))
            continue
        for c in _COLOURS:
            p = e["planes"][c]
            zone = c == "green"
            rows.append((e["id"], c, _f(p["f_grid_cy_per_px"], 3), _f(p["measured_at_grid_nyquist"]),
                         _f(p["predicted_at_grid_nyquist"]),
                         _f(p["measured_at_grid_nyquist"] - p["predicted_at_grid_nyquist"], 4),
                         _f(p["f_zone_cy_per_px"], 3) if zone else "–",
                         _f(p["measured_at_zone_nyquist"]) if zone else "–",
                         _f(p["predicted_at_zone_nyquist"]) if zone else "–",
                         _f(p["alias_cy_per_px"], 3), p["sampling"]))  # fmt: skip
    cols = ("edge", "plane", "grid Nyquist (cy/px)", "MTF measured", "predicted", "error",
            "quincunx Nyquist (cy/px)", "MTF measured", "predicted", "aliases to 0 at (cy/px)", "sampling")  # fmt: skip
    note = ("Each raw colour plane measured on its own grid by the slanted-edge method, along the edge normal, "
            "against the colour's system MTF there (frequencies in cycles per pixel of the full array). Green: "
            "also at its quincunx's own Nyquist along the normal (about 1/(2p) near the axes).")  # fmt: skip
    return FocalTable("Colour planes: MTF at each plane's Nyquist, measured vs predicted", cols, tuple(rows), note)


def _methods_table(data: Mapping[str, Any]) -> FocalTable:
    rows = tuple(
        (m["label"], _f(m["luminance_mtf50_cy_per_px"]), _f(m["luminance_mtf50_predicted"]),
         _f(m["false_colour_peak"]), _f(m["false_colour_rms"]), _f(m["flat_false_colour_peak"]))
        for m in data.get("methods", ())
    )  # fmt: skip
    cols = ("demosaicing", "luminance MTF50 (cy/px)", "predicted (perfect interpolation)", "false colour peak",
            "false colour rms", "peak away from the edge")  # fmt: skip
    edge = data.get("methods_edge")
    why = data.get("methods_reason") or "no neutral edge was measured"
    note = (f"At the neutral edge {edge}: the BT.709 luminance's MTF50, and the chroma across the edge "
            "(sqrt(((R-G)^2 + (B-G)^2)/2)) within 4 px of it as a fraction of the edge step; reported side by "
            "side, not checked." if edge else f"n/a: {why}")  # fmt: skip
    return FocalTable("Demosaicing methods side by side", cols, rows, note)


def parts(data: Mapping[str, Any], fig_dir: Path) -> FocalParts:
    """The cfa section's words, tables and figures (drawn into ``fig_dir``)."""
    resp = data.get("responses", {})
    sources = sorted(set(resp.values()))
    text = (f"The camera has a Bayer colour filter array ({data.get('pattern')}); the run's main image above is its "
            f"base array. Here the raw mosaic of the same scene ({data.get('units')}"
            f"{', noisy' if data.get('noise') else ', noise-free'}) is measured plane by plane, and demosaiced. "
            "Colour responses: " + "; ".join(f"{', '.join(c for c, s in resp.items() if s == src)}: {src}"
                                             for src in sources) + ".")  # fmt: skip
    if data.get("units_note"):
        text += f" {data['units_note']}."
    figures = []
    ref = _reference_edge(data)
    if ref is not None:
        plot_plane_mtf(ref, fig_dir / MTF_FIGURE)
        figures.append((MTF_FIGURE, f"Each raw colour plane's MTF along the normal of edge {ref['id']}, measured on "
                        "its own grid (dots) and predicted (line); dashed: the plane's grid Nyquist, dotted (green): "
                        "its quincunx's Nyquist, dash-dot: the frequency it aliases back to zero."))  # fmt: skip
    if data.get("crop"):
        plot_crops(data["crop"], data.get("methods", ()), fig_dir / CROPS_FIGURE)
        figures.append((CROPS_FIGURE, f"Edge {data['crop']['edge']} demosaiced by each method (and the colour planes "
                        "themselves), the same linear stretch for all: false colour shows as fringes."))  # fmt: skip
    return FocalParts("focal-cfa", str(data.get("title", "Colour filter array")), text,
                      (_plane_table(data), _methods_table(data)), tuple(figures))  # fmt: skip


def _reference_edge(data: Mapping[str, Any]) -> Mapping[str, Any] | None:
    """The methods' edge if measured, else the first measured edge."""
    ok = [e for e in data.get("edges", ()) if not e.get("reason") and e.get("curves")]
    want = data.get("methods_edge")
    return next((e for e in ok if e["id"] == want), ok[0] if ok else None)


def plot_plane_mtf(edge: Mapping[str, Any], path: Path) -> None:
    """One panel per colour plane: its MTF along the edge normal measured (dots) and predicted (line), its grid
    Nyquist (dashed), green's quincunx Nyquist (dotted) and where it aliases to zero (dash-dot)."""
    curves = edge["curves"]
    f = np.asarray(curves["f_cy_per_px"], float)
    with matplotlib.rc_context(rc_for(13)):
        fig = Figure(figsize=(12, 4.0), dpi=100)
        axes = [fig.add_axes((0, 0, 1, 1)) for _ in _COLOURS]
        for ax, c in zip(axes, _COLOURS, strict=True):
            meas = np.asarray([np.nan if v is None else v for v in curves[c]["measured"]], float)
            ax.plot(f, curves[c]["predicted"], color=_LINE[c], lw=1.2, label="predicted")
            ax.plot(f, meas, ".", color="k", ms=3, label="measured")
            p = edge["planes"][c]
            ax.axvline(p["f_grid_cy_per_px"], color="0.3", ls="--", lw=0.8, label="grid Nyquist")
            if c == "green":
                ax.axvline(p["f_zone_cy_per_px"], color="0.3", ls=":", lw=0.9, label="quincunx Nyquist")
            if p["alias_cy_per_px"] <= f[-1]:
                ax.axvline(p["alias_cy_per_px"], color="0.3", ls="-.", lw=0.8, label="aliases to 0")
            ax.set_xlim(0, f[-1])
            ax.set_ylim(0, 1.05)
            ax.set_xlabel("f along the normal (cy/px)")
            ax.set_ylabel("MTF")
            ax.set_title(f"{c} plane ({'quincunx' if c == 'green' else '2 px grid'})")
            ax.grid(alpha=0.3)
            ax.legend(loc="upper right", fontsize="small")
        place_grid(fig, [axes], top=title_band_in(), bottom=axis_band_in(), right=0.4)
        save_figure(fig, path, dpi=100)


def plot_crops(crop: Mapping[str, Any], methods, path: Path) -> None:
    """The crop of the reference edge as each method demosaiced it, side by side (one linear stretch)."""
    labels = {m["method"]: m["label"] for m in methods}
    keys = list(crop["rgb"])
    top = float(crop.get("display_max") or 1.0)
    with matplotlib.rc_context(rc_for(10)):
        fig = Figure(figsize=(2.5 * len(keys), 3.0), dpi=100)
        axes = [fig.add_axes((0, 0, 1, 1)) for _ in keys]
        for ax, k in zip(axes, keys, strict=True):
            img = np.clip(np.asarray(crop["rgb"][k], float) / top, 0.0, 1.0)
            ax.imshow(img, interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            name = labels.get(k, k)
            ax.set_title("colour planes (noise-free)" if k == "true" else name)
        place_grid(fig, [axes], top=title_band_in(), bottom=0.1, left=0.1, hgap=0.15)
        save_figure(fig, path, dpi=100)
