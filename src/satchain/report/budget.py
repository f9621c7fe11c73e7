"""Assemble the MTF/CTF budget of a system into JSON-ready results, tables and figures.

This is where prediction is packaged for people: ``satchain budget`` prints
:func:`satchain.prediction.budget.budget_results` (computed there, in the prediction layer; still importable
from here) and, with ``-o DIR``, :func:`write_budget_outputs` writes ``budget.json``, ``mtf_alt.csv``,
``mtf_act.csv``, ``fig2_spectral_radiance.png``, ``fig3a_mtf_budget.png`` and ``fig3b_square_wave.png``.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from satchain.config.system import ImagingSystem
from satchain.prediction.budget import DirectionalMTF, budget_results
from satchain.tf import ctf as _ctf
from satchain.tf.budget import DIRECTIONS, SystemOTF, mtf_budget

__all__ = ["DirectionalMTF", "budget_results", "square_wave_figure_data", "write_budget_outputs"]

#: The paper's Figure 3(b) bar period on the ground.
FIG3B_PERIOD_M = 16.0


def square_wave_figure_data(system: ImagingSystem, *, period_m: float = FIG3B_PERIOD_M, otf: SystemOTF | None = None):
    """Positions (ground m), input and ALT-degraded truncated square-wave series for Figure 3(b)."""
    otf = SystemOTF(system) if otf is None else otf
    x = np.linspace(0.0, 2.0 * period_m, 2001)
    scale = system.focal_cy_per_mm_per_ground_cy_per_m("alt")
    square = _ctf.square_wave_series(x, period_m)
    degraded = _ctf.square_wave_series(x, period_m, mtf=DirectionalMTF(otf, "alt"), f_unit_scale=scale)
    return x, np.asarray(square), np.asarray(degraded)


def _csv_text(results: dict[str, Any], d: str) -> str:
    comps = list(results["mtf"][d])
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(
        [
            "f_cy_per_mm",
            "f_cy_per_px",
            "f_cy_per_m_ground",
            *[f"mtf_{c}" for c in comps],
            "ctf_coltman",
            "ctf_fourier_synthesis",
        ]
    )
    cols = [
        results["frequencies_cy_per_mm"],
        results["frequencies_cy_per_px"][d],
        results["frequencies_cy_per_m_ground"][d],
        *[results["mtf"][d][c] for c in comps],
        results["ctf"][d]["coltman"],
        results["ctf"][d]["fourier_synthesis"],
    ]
    for row in zip(*cols, strict=True):
        w.writerow([f"{v:.6g}" for v in row])
    return buf.getvalue()


def write_budget_outputs(
    system: ImagingSystem, results: dict[str, Any], out_dir: str | Path, *, otf=None
) -> list[Path]:
    """Write JSON, CSV tables and the Figure 3(a)/(b) plots into ``out_dir``; return the paths written."""
    from satchain.report import figures
    from satchain.report._save import write_text

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    p = out / "budget.json"
    write_text(p, json.dumps(results, indent=2))
    written.append(p)
    for d in DIRECTIONS:
        p = out / f"mtf_{d}.csv"
        write_text(p, _csv_text(results, d))
        written.append(p)
    otf = SystemOTF(system) if otf is None else otf
    f_dense = np.linspace(0.0, float(np.max(results["frequencies_cy_per_mm"])), 341)
    dense = budget_results(system, f_dense, otf=otf)  # the plot wants smooth curves, not the table grid
    b = mtf_budget(system, f_dense, otf=otf)
    p = out / "fig3a_mtf_budget.png"
    figures.plot_mtf_budget(b, p, ctf=dense["ctf"], title=f"MTF budget: {system.name}")
    written.append(p)
    x, sq, deg = square_wave_figure_data(system, otf=otf)
    p = out / "fig3b_square_wave.png"
    figures.plot_square_wave(x, sq, deg, p, period_m=FIG3B_PERIOD_M, note="ALT, 10 odd harmonics")
    written.append(p)
    from satchain.radiometry import radiometric_budget
    from satchain.report.radiometry_plot import plot_spectral_radiance

    p = out / "fig2_spectral_radiance.png"
    plot_spectral_radiance(radiometric_budget(system), p)
    written.append(p)
    return written
