"""The report's staggered part (:mod:`satchain.report.focal_plane`): the two arrays combined onto the half-pitch
grid, from results.json's ``staggered`` entry (:mod:`satchain.focal.staggered`) alone -- a table of the edges at
both Nyquists, a table of the bar groups (period in one array's pixels, CTF measured and predicted, resolved?) and
a figure of the combined MTF predicted against the edges' measured MTF, both Nyquists marked, the alias regions
shaded."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from satchain.report._save import save_figure
from satchain.report.focal_parts import FocalParts, FocalTable

__all__ = ["FIGURE", "parts"]

#: The figure's file name in the report's figure folder.
FIGURE = "staggered_mtf.png"


def _num(v: Any, fmt: str = ".3f") -> str:
    return "n/a" if v is None or not np.isfinite(float(v)) else format(float(v), fmt)


def _verdict(passed: Any) -> str:
    return "n/a" if passed is None else "pass" if passed else "FAIL"


def _edge_table(data: Mapping[str, Any]) -> FocalTable:
    rows = []
    for e in data.get("edges", []):
        c, s = e.get("combined_nyquist", {}), e.get("single_nyquist", {})
        rows.append((f"{e['id']} ({e['direction']})", _num(c.get("measured")), _num(c.get("predicted")),
                     _num(c.get("sigma"), ".4f"), _verdict(c.get("pass")), _num(s.get("measured")),
                     _num(s.get("predicted")), _num(s.get("sigma"), ".4f"), _verdict(s.get("pass"))))  # fmt: skip
    ny = data.get("nyquist_cy_per_mm", {})
    return FocalTable(
        "Edges on the combined grid: MTF along the edge normal",
        (
            "edge",
            "combined Nyquist: measured",
            "predicted",
            "sigma",
            "result",
            "one array's Nyquist: measured",
            "predicted",
            "sigma",
            "result",
        ),
        tuple(rows),
        note=f"combined Nyquist 1/p = {_num(ny.get('combined_axis'), '.1f')} cy/mm, one array's 1/(2p) = "
        f"{_num(ny.get('single_array'), '.1f')} cy/mm on the focal plane. Predicted: {data.get('prediction', '')}; "
        "where the model's MTF is within 3 sigma of 0 the Rice mean of MTF + noise is compared.",
    )


def _bar_table(data: Mapping[str, Any]) -> FocalTable:
    rows = []
    for b in data.get("bars", []):
        for g in b.get("groups", []):
            if not g.get("compared"):
                verdict = f"not compared: {g.get('not_compared') or 'no CTF measured'}"
            else:
                verdict = "as predicted" if g.get("resolved_as_predicted") else "NOT as predicted"
            alias = g.get("single_alias_period_px")
            one = "aliases" + (f" (to {alias:.2f} px)" if alias else "") if g.get("beyond_single_nyquist") else "yes"
            rows.append((f"{b['id']} ({b['direction']}) group {g['group']}", _num(g.get("period_single_px"), ".2f"),
                         one, _num(g.get("ctf_measured")), _num(g.get("ctf_predicted")),
                         "yes" if g.get("resolved_measured") else "no", verdict))  # fmt: skip
    for sk in data.get("skipped", []):  # groups (or targets) the combined grid could not measure
        if str(sk.get("kind", "")).startswith("bar"):
            rows.append((str(sk.get("id")), "", "", "n/a", "", "", f"not measured: {sk.get('reason')}"))
    thr = data.get("resolution_threshold")
    return FocalTable(
        "Bar groups on the combined grid: CTF against Coltman's of the combined MTF",
        (
            "group",
            "period (px of one array)",
            "one array samples it?",
            "CTF measured",
            "CTF predicted",
            "resolved?",
            "vs prediction",
        ),
        tuple(rows),
        note=f"resolved: CTF >= {_num(thr, 'g')} (the run's contrast threshold); a period below 2 px of one array "
        "lies above its Nyquist: one array alone aliases it, the combined grid samples it up to 1 px.",
    )


def _figure(data: Mapping[str, Any], path: Path) -> None:
    ny = data.get("nyquist_cy_per_mm", {})
    single, comb = float(ny.get("single_array", np.nan)), float(ny.get("combined_axis", np.nan))
    curves = data.get("mtf_curves", {})
    fig = Figure(figsize=(7.2, 4.2), dpi=100)
    ax = fig.add_axes((0.1, 0.13, 0.62, 0.8))
    f = np.asarray(curves.get("f_cy_per_mm", []), float)
    top = float(f[-1]) if f.size else 1.5 * comb
    ax.axvspan(single, comb, color="0.9", lw=0, label="one array aliases")
    ax.axvspan(comb, top, color="#f4cccc", lw=0, label="combined grid aliases")
    for key, style in (("act", "-"), ("alt", "--")):
        if key in curves:
            ax.plot(f, curves[key], "k" + style, lw=1.2, label=f"predicted, {key.upper()}")
    for e in data.get("edges", []):
        fe, m = np.asarray(e.get("f_cy_per_mm", []), float), e.get("mtf_measured", [])
        mm = np.asarray([np.nan if v is None else v for v in m], float)
        if fe.size and fe.size == mm.size:
            keep = fe <= top
            ax.plot(fe[keep], mm[keep], lw=1.0, alpha=0.85, label=f"measured: {e['id']}")
    for x, name in ((single, "1/(2p)"), (comb, "1/p")):
        ax.axvline(x, color="0.3", lw=0.8, ls=":")
        ax.annotate(name, (x, 1.02), ha="center", va="bottom", fontsize=8, xycoords=("data", "axes fraction"))
    ax.set_xlim(0, top)
    ax.set_ylim(-0.02, 1.05)
    ax.set_xlabel("spatial frequency on the focal plane (cy/mm)")
    ax.set_ylabel("MTF on the combined grid")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, frameon=False)
    save_figure(fig, path)


def parts(data: Mapping[str, Any], fig_dir: Path) -> FocalParts:
    """The staggered section's words, tables and figures (drawn into ``fig_dir``)."""
    title = str(data.get("title", "staggered"))
    if data.get("not_simulated"):
        return FocalParts("focal-staggered", title, text=f"Not simulated: {data['not_simulated']}.")
    comb = data.get("combination", {})
    p, g = data.get("pitch_m"), data.get("gsd_m") or [None]
    beyond = data.get("beyond_single_nyquist_resolved") or []
    text = (
        f"Two arrays of {_num(None if p is None else p * 1e6, '.3g')} um pixels ({_num(g[0], '.3g')} m GSD), array B "
        f"half a pixel along and across track from array A, imaged ({data.get('simulated', 'as designed')}) from the "
        f"run's scene and combined onto the grid of half the pitch ({_num(None if p is None else p * 5e5, '.3g')} "
        f"um). Combination: {comb.get('description', comb.get('method', ''))}; its transfer function "
        f"{comb.get('transfer_function', '')}. {data.get('aliasing', '')}. The main run above measures array A "
        f"alone. Bar groups above one array's Nyquist that the combination resolves: "
        f"{', '.join(beyond) if beyond else 'none'}."
    )
    _figure(data, fig_dir / FIGURE)
    caption = (
        "The combined grid's MTF: predicted (system MTF x the combination's transfer function, along ACT and ALT) "
        "and measured on each slanted edge along its normal; dotted: one array's Nyquist 1/(2p) and the combined "
        "Nyquist 1/p; grey: where one array alone aliases and the combination samples; red: aliased on the "
        "combined grid."
    )
    return FocalParts("focal-staggered", title, text=text, tables=(_edge_table(data), _bar_table(data)),
                      figures=((FIGURE, caption),))  # fmt: skip
