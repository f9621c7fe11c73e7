"""Assemble the MTF/CTF budget of a system into JSON-ready results, tables and figures.

This is where prediction is packaged for people: ``satchain budget`` prints :func:`budget_results`
and, with ``-o DIR``, :func:`write_budget_outputs` writes ``budget.json``, ``mtf_alt.csv``,
``mtf_act.csv``, ``fig2_spectral_radiance.png``, ``fig3a_mtf_budget.png`` and ``fig3b_square_wave.png``.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from satchain import units
from satchain.config.system import ImagingSystem
from satchain.tf import ctf as _ctf
from satchain.tf.budget import DIRECTIONS, SystemOTF, _cut, mtf_at_nyquist, mtf_budget, mtfa

__all__ = ["DirectionalMTF", "budget_results", "square_wave_figure_data", "write_budget_outputs"]

#: The paper's Figure 3(b) bar period on the ground.
FIG3B_PERIOD_M = 16.0


class DirectionalMTF:
    """The system MTF along one axis as a callable of focal-plane frequency (cy/mm), with its cutoff."""

    def __init__(self, otf: SystemOTF, direction: str):
        self._otf, self.direction = otf, direction
        self.cutoff = float(np.max(otf.system.optical_cutoff_cy_per_mm))

    def __call__(self, f_cy_per_mm) -> np.ndarray:
        f = np.asarray(f_cy_per_mm, dtype=float)
        return np.abs(self._otf(*_cut(self.direction, f)))


def _pitch(system: ImagingSystem, d: str) -> float:
    return system.detector.pitch_y_m if d == "alt" else system.detector.pitch_x_m


def budget_results(system: ImagingSystem, f_cy_per_mm=None, *, otf: SystemOTF | None = None) -> dict[str, Any]:
    """Derived quantities, MTF per component, CTF (Coltman and the paper's synthesis), MTF at Nyquist, MTFA."""
    otf = SystemOTF(system) if otf is None else otf
    b = mtf_budget(system, f_cy_per_mm, otf=otf)
    f = b.f_cy_per_mm
    out: dict[str, Any] = {"system": system.name, "derived": system.derived()}
    out.update(b.to_dict())
    out["frequencies_cy_per_px"] = {
        d: units.cy_per_mm_to_cy_per_px(f, pitch_m=_pitch(system, d)).tolist() for d in DIRECTIONS
    }
    out["frequencies_cy_per_m_ground"] = {
        d: (f / system.focal_cy_per_mm_per_ground_cy_per_m(d)).tolist() for d in DIRECTIONS
    }
    out["ctf"] = {}
    out["mtfa"] = {}
    for d in DIRECTIONS:
        m = DirectionalMTF(otf, d)
        out["ctf"][d] = {
            "coltman": np.asarray(_ctf.coltman_ctf(f, m)).tolist(),
            "fourier_synthesis": np.asarray(_ctf.ctf_fourier_synthesis(f, m)).tolist(),
        }
        fpx = np.linspace(0.0, 0.5, 257)
        fmm = units.cy_per_px_to_cy_per_mm(fpx, pitch_m=_pitch(system, d))
        out["mtfa"][d] = mtfa(fpx, m(fmm), f_max_cy_per_px=0.5)
    out["mtf_at_nyquist"] = mtf_at_nyquist(system, otf=otf)
    pb = getattr(otf, "pushbroom", None)
    geometry = pb.geometry() if pb is not None else None
    if geometry is not None:
        out["motion_geometry"] = geometry  # line displacement, TDI drift, Earth-rotation shear/scale/rotation
    from satchain.prediction.quality import predict_quality
    from satchain.radiometry import radiometric_budget

    out["radiometry"] = radiometric_budget(system).to_dict()
    out["quality"] = predict_quality(system, otf=otf).to_dict()
    out["frequency_axis"] = (
        "the detector pixel's axis (cy/mm on the focal plane, cy/px of the detector pitch, cy/m at the design GSD); "
        "an image with a line-rate error or Earth rotation has its rows motion_geometry.alt_scale detector px "
        "apart on the ground, and `run` predicts on the image's axis (f_y / alt_scale); the pushbroom motion "
        "terms are their signed expected OTF"
    )
    out["ctf_notes"] = (
        "coltman: the square-wave (bar) response by Coltman's series (physical, -> 1 at low frequency, "
        "4/pi*MTF near cutoff); fourier_synthesis: the reference paper's method (10 odd harmonics, modulation of "
        "the degraded truncated series / modulation of the input truncated series), which divides by the "
        "Gibbs overshoot of the truncated input (~1.18)."
    )
    return out


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
