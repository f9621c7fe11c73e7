"""The report's bands part (:mod:`satchain.report.focal_plane`): a ``[[bands]]`` run's per-band table and figures,
drawn from results.json's ``bands`` entry alone (:mod:`satchain.focal.bands` writes it).

- the table: per band its centre wavelength, GSD, edge MTF at its own Nyquist (measured vs predicted), SNR
  (measured vs predicted) and offset from the PAN band (ACT, ALT: measured +- 1-sigma vs predicted, z);
- ``bands_mtf.png``: every band's predicted MTF (ACT solid, ALT dashed) against focal-plane frequency, the edges'
  measured MTF as points, each band's Nyquist marked;
- ``bands_registration.png``: each band's registration vector from the PAN position (measured arrow, predicted
  cross, 1-sigma ellipse magnified by a stated factor), and per row strip where the line of sight moves in time.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from satchain.report.focal_parts import FocalParts, FocalTable

__all__ = ["MTF_FIGURE", "REGISTRATION_FIGURE", "parts"]

MTF_FIGURE = "bands_mtf.png"
REGISTRATION_FIGURE = "bands_registration.png"
#: A band's line colour by name, else by centre wavelength (:func:`_colour`).
_NAMED = {"pan": "0.15", "blue": "tab:blue", "green": "tab:green", "red": "tab:red", "nir": "tab:purple"}


def parts(data: Mapping[str, Any], fig_dir: Path) -> FocalParts:
    """The bands section's words, tables and figures (drawn into ``fig_dir``)."""
    bands = list(data.get("bands") or [])
    ref = str(data.get("reference_band", "pan"))
    noise = "noisy" if data.get("noise") else "noise-free"
    text = (f"Every band formed from the scene on its own pixel grid ({noise}, {data.get('units', '')}; the camera "
            f"{data.get('system_formed', 'design')}), each measured on its own image: its slanted edges' MTF at its "
            f"own Nyquist (0.5 cy/px of the band), its SNR on the clear background, and its offset from the {ref} band "
            "(registration, in the band's pixels: its content relative to the reference's), each against the "
            "band's budget.")  # fmt: skip
    figures: list[tuple[str, str]] = []
    if bands:
        _mtf_figure(bands, fig_dir / MTF_FIGURE)
        figures.append((MTF_FIGURE, "The bands' MTF: predicted along ACT (solid) and ALT (dashed) against "
                        "focal-plane frequency, the slanted edges' measured MTF as points, each band's Nyquist "
                        "dotted."))  # fmt: skip
    if any(b.get("registration") for b in bands):
        mag = _registration_figure(bands, fig_dir / REGISTRATION_FIGURE)
        figures.append((REGISTRATION_FIGURE, f"Registration vector of each band from the {ref} position (band "
                        f"px; ALT down): measured (arrow) and predicted (cross), 1-sigma ellipse x{mag:g}; per "
                        "row strip (thin arrows, predicted path dotted; below: each strip's offset against its row, "
                        "measured +- 1-sigma as points, predicted as lines) where the line of sight moves in "
                        "time."))  # fmt: skip
    return FocalParts("focal-bands", str(data.get("title", "bands")), text, (_table(bands, ref),), tuple(figures))


# --------------------------------------------------------------------------------------------------- the table


def _f(v: Any, fmt: str = ".4f") -> str:
    return "n/a" if v is None or not math.isfinite(float(v)) else format(float(v), fmt)


def _edges_cell(edges: Sequence[Mapping[str, Any]]) -> str:
    if not edges:
        return "no slanted edge"
    return "; ".join(f"{e['direction']} {_f(e.get('measured'))} / {_f(e.get('predicted'))}" for e in edges)


def _offset_cell(reg: Mapping[str, Any] | None, d: str) -> str:
    if reg is None:
        return "reference"
    pred = (reg.get("predicted_px") or {}).get(d)
    m = reg.get("measured_px")
    if m is None:
        return f"n/a / {_f(pred, '+.3f')}"
    return f"{_f(m[d], '+.3f')} ± {_f(reg['sigma_px'][d], '.3f')} / {_f(pred, '+.3f')}"


def _z_cell(reg: Mapping[str, Any] | None) -> str:
    if not reg or not reg.get("z"):
        return ""
    return ", ".join(_f(reg["z"].get(d), "+.2f") for d in ("act", "alt"))


def _table(bands: list[Mapping[str, Any]], ref: str) -> FocalTable:
    rows: list[tuple[str, ...]] = []
    notes: dict[str, list[str]] = {}  # reason -> what it applies to
    for b in bands:
        snr = b.get("snr") or {}
        reg = b.get("registration")
        rows.append((
            str(b["name"]), _f(b["center_wavelength_m"] * 1e9, ".0f"), _f(b["gsd_m"], ".3g"),
            _edges_cell(b.get("edges") or ()), f"{_f(snr.get('measured'), '.1f')} / {_f(snr.get('predicted'), '.1f')}",
            _offset_cell(reg, "act"), _offset_cell(reg, "alt"), _z_cell(reg),
        ))  # fmt: skip
        for e in b.get("edges") or ():
            if e.get("reason"):
                notes.setdefault(str(e["reason"]), []).append(f"{b['name']} edge {e['id']}")
        if snr.get("reason"):
            notes.setdefault(str(snr["reason"]), []).append(f"{b['name']} SNR")
        if reg and reg.get("reason"):
            notes.setdefault(str(reg["reason"]), []).append(f"{b['name']} offset")
    note = ("Measured / predicted. Edge MTF at the band's own Nyquist (0.5 cy/px along the edge normal); SNR: signal "
            f"SNR of the clear background; offset from {ref}: the band's content relative to the reference's, band "
            "px (± 1-sigma), "
            "z = (measured - predicted) / sigma.")  # fmt: skip
    for why, what in notes.items():
        note += f" n/a ({', '.join(what)}): {why}."
    columns = ("band", "centre (nm)", "GSD (m)", "edge MTF@Nyquist", "SNR", "offset ACT (px)", "offset ALT (px)",
               "z (ACT, ALT)")  # fmt: skip
    return FocalTable("Per band: measured vs predicted", columns, tuple(rows), note)


# ------------------------------------------------------------------------------------------------- the figures


def _colour(b: Mapping[str, Any]) -> Any:
    name = str(b.get("name", "")).casefold()
    if name in _NAMED:
        return _NAMED[name]
    from matplotlib import colormaps

    lam = float(b.get("center_wavelength_m", 6e-7)) * 1e9
    return colormaps["turbo"](min(max((lam - 400.0) / 600.0, 0.0), 1.0))


def _mtf_figure(bands: list[Mapping[str, Any]], path: Path) -> None:
    from matplotlib.figure import Figure

    from satchain.report._save import save_figure

    fig = Figure(figsize=(7.0, 4.2))
    ax = fig.add_axes((0.1, 0.13, 0.64, 0.8))
    f_max = 0.0
    for b in bands:
        col, c = _colour(b), b["mtf_curve"]
        pitch_mm = float(b["pitch_m"]) * 1e3
        ax.plot(c["f_cy_per_mm_act"], c["act"], color=col, lw=1.4, label=f"{b['name']} ({_f(b['gsd_m'], '.3g')} m)")
        ax.plot(c["f_cy_per_mm_alt"], c["alt"], color=col, lw=1.0, ls="--")
        ny = float(b["nyquist_cy_per_mm"]["act"])
        ax.axvline(ny, color=col, lw=0.8, ls=":")
        f_max = max(f_max, ny)
        for e in b.get("edges") or ():
            f = [v / pitch_mm for v in e.get("f_cy_per_px") or ()]
            ax.plot(f, e.get("mtf_measured") or [], ls="none", marker="o" if e["direction"] == "ACT" else "s",
                    ms=2.2, color=col, alpha=0.6)  # fmt: skip
            if e.get("measured") is not None:
                ax.plot([0.5 / pitch_mm], [e["measured"]], ls="none", marker="D", ms=5, mfc="white", mec=col)
    ax.set_xlim(0.0, 1.15 * f_max if f_max > 0 else None)
    ax.set_ylim(0.0, 1.05)
    ax.set_xlabel("spatial frequency on the focal plane (cy/mm)")
    ax.set_ylabel("MTF")
    ax.grid(alpha=0.3)
    handles, labels = ax.get_legend_handles_labels()
    from matplotlib.lines import Line2D

    handles += [Line2D([], [], color="0.3", lw=1.4), Line2D([], [], color="0.3", lw=1.0, ls="--"),
                Line2D([], [], color="0.3", ls="none", marker="o", ms=3),
                Line2D([], [], color="0.3", ls="none", marker="D", ms=5, mfc="white")]  # fmt: skip
    labels += ["predicted ACT", "predicted ALT", "edge measured", "at its Nyquist"]
    fig.legend(handles, labels, loc="center left", bbox_to_anchor=(0.76, 0.53), fontsize=8, frameon=False)
    save_figure(fig, path)


def _magnification(regs: list[Mapping[str, Any]], span: float) -> float:
    """A power of 10 that makes the median 1-sigma ~1/20 of the panels' span visible (at least 1)."""
    sig = sorted(max(r["sigma_px"].values()) for r in regs if r.get("sigma_px"))
    if not sig or sig[len(sig) // 2] <= 0:
        return 1.0
    return float(max(1.0, 10.0 ** math.floor(math.log10(span / 20.0 / sig[len(sig) // 2]))))


def _extent(shown: list[Mapping[str, Any]]) -> float:
    """Half the side of the vector panels (band px): every offset shown fits, at least 0.1 px."""
    pts = [0.0]
    for b in shown:
        r = b["registration"]
        for item in (r, *(r.get("strips") or ())):
            for key in ("measured_px", "predicted_px"):
                if item.get(key):
                    pts += [abs(item[key]["act"]), abs(item[key]["alt"])]
    return max(max(pts) * 1.25, 0.1)


def _vector_panel(ax, b: Mapping[str, Any], half: float, mag: float) -> None:
    """Band ``b``'s registration vector: measured arrow from the reference position, its 1-sigma ellipse (x ``mag``),
    the predicted offset (cross), each strip's measured arrow and the strips' predicted path."""
    from matplotlib.patches import Ellipse

    r, col = b["registration"], _colour(b)
    ax.axhline(0, color="0.8", lw=0.6)
    ax.axvline(0, color="0.8", lw=0.6)
    strips = [s for s in r.get("strips") or () if s.get("predicted_px")]
    if strips:
        ax.plot([s["predicted_px"]["act"] for s in strips], [s["predicted_px"]["alt"] for s in strips], color=col,
                ls=":", lw=0.9)  # fmt: skip
        for s in strips:
            if s.get("measured_px"):
                ax.annotate("", xy=(s["measured_px"]["act"], s["measured_px"]["alt"]), xytext=(0, 0),
                            arrowprops={"arrowstyle": "->", "color": col, "lw": 0.6, "alpha": 0.6})  # fmt: skip
    p, m = r.get("predicted_px"), r.get("measured_px")
    if p:
        ax.plot([p["act"]], [p["alt"]], marker="x", ms=7, color="k", ls="none")
    if m:
        ax.annotate("", xy=(m["act"], m["alt"]), xytext=(0, 0), arrowprops={"arrowstyle": "-|>", "color": col,
                                                                          "lw": 1.6})  # fmt: skip
        sg = r["sigma_px"]
        ax.add_patch(Ellipse((m["act"], m["alt"]), 2 * mag * sg["act"], 2 * mag * sg["alt"], fill=False, color=col,
                             lw=1.0))  # fmt: skip
    else:
        ax.text(0.5, 0.08, "not measured (n/a)", transform=ax.transAxes, ha="center", fontsize=8, color="0.4")
    ax.set_xlim(-half, half)
    ax.set_ylim(half, -half)  # ALT down, as the image's rows
    ax.set_aspect("equal")
    ax.set_title(str(b["name"]), fontsize=9, color=col)
    ax.set_xlabel("ACT offset (band px)", fontsize=8)
    ax.tick_params(labelsize=7)


def _strip_panel(ax, b: Mapping[str, Any]) -> None:
    """Band ``b``'s offset per row strip: measured (ACT filled, ALT open, +- 1-sigma) and predicted (lines)."""
    col = _colour(b)
    strips = [s for s in b["registration"].get("strips") or () if s.get("predicted_px")]
    mid = [(s["rows"][0] + s["rows"][1]) / 2.0 for s in strips]
    for d, face, ls in (("act", col, "-"), ("alt", "white", "--")):
        ax.plot(mid, [s["predicted_px"][d] for s in strips], color=col, ls=ls, lw=1.0)
        got = [(x, s["measured_px"][d], s["sigma_px"][d]) for x, s in zip(mid, strips, strict=True)
               if s.get("measured_px")]  # fmt: skip
        if got:
            x, y, e = zip(*got, strict=True)
            ax.errorbar(x, y, yerr=e, ls="none", marker="o", ms=3.5, mfc=face, mec=col, ecolor=col, lw=0.8)
    ax.set_xlabel("band row (strip centre)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(alpha=0.3)


def _registration_figure(bands: list[Mapping[str, Any]], path: Path) -> float:
    from matplotlib.figure import Figure

    from satchain.report._save import save_figure

    shown = [b for b in bands if b.get("registration")]
    half = _extent(shown)
    mag = _magnification([b["registration"] for b in shown], 2 * half)
    n = len(shown)
    cols = min(n, 4)
    nrows = math.ceil(n / cols)
    with_strips = any(b["registration"].get("strips") for b in shown)
    total = 2 * nrows if with_strips else nrows
    fig = Figure(figsize=(2.6 * cols + 0.4, 2.6 * total + 0.5))
    for k, b in enumerate(shown):
        ax = fig.add_subplot(total, cols, k + 1)
        _vector_panel(ax, b, half, mag)
        if k % cols == 0:
            ax.set_ylabel("ALT offset (band px)", fontsize=8)
        if with_strips and b["registration"].get("strips"):
            sx = fig.add_subplot(total, cols, nrows * cols + k + 1)
            _strip_panel(sx, b)
            if k % cols == 0:
                sx.set_ylabel("offset per strip (band px)\nACT filled, ALT open", fontsize=8)
    fig.subplots_adjust(left=0.1, right=0.97, bottom=0.1, top=0.93, wspace=0.35, hspace=0.45)
    save_figure(fig, path)
    return mag
