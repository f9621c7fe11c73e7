"""Figures of the MTF budget: the paper's Figure 3(a) (MTF components) and 3(b) (square-wave series)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure

from satchain.report._save import save_figure
from satchain.report._style import axis_band_in, legend_height_in, place_grid, text_height_in, title_band_in
from satchain.report.compare_plots import with_rc

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["plot_mtf_budget", "plot_square_wave"]

_STYLE: dict[str, dict[str, Any]] = {
    "diffraction": dict(color="tab:orange"),
    "detector": dict(color="tab:green"),
    "smear": dict(color="tab:purple"),
    "jitter": dict(color="tab:brown"),
    "charge_diffusion": dict(color="tab:olive"),
    "tdi_sync": dict(color="tab:cyan"),
    "tdi_drift": dict(color="tab:cyan", linestyle="--"),
    "jitter_psd_act": dict(color="tab:brown", linestyle="--"),
    "jitter_psd_alt": dict(color="tab:brown", linestyle=":"),
    "system": dict(color="black", linewidth=2.2),
}


@with_rc(9.6)
def plot_mtf_budget(budget, path: str | Path, *, ctf: dict | None = None, title: str = "") -> None:
    """MTF of each component and of the system vs focal-plane frequency, ALT and ACT panels.

    ``budget`` is a :class:`satchain.tf.budget.MTFBudget`; ``ctf`` optionally maps direction ->
    {"coltman": [...], "fourier_synthesis": [...]} on the same frequencies.
    """
    f = budget.f_cy_per_mm
    fig = Figure(figsize=(9.6, 5.8), dpi=100)  # a fixed layout in inches, placed below (_style.place_grid)
    a0 = fig.add_axes((0, 0, 1, 1))
    axes = [a0, fig.add_axes((0, 0, 1, 1), sharey=a0)]
    axes[1].tick_params(labelleft=False)
    for ax, d in zip(axes, ("alt", "act"), strict=True):
        for name, m in getattr(budget, d).items():
            if name != "system" and np.allclose(m, 1.0):
                continue  # a component that does not act along this axis (e.g. ALT smear in ACT)
            ax.plot(f, m, label=f"{name} MTF", **_STYLE.get(name, {}))
        if ctf is not None:
            ax.plot(f, ctf[d]["coltman"], "--", color="tab:red", label="CTF (Coltman)")
            ax.plot(f, ctf[d]["fourier_synthesis"], ":", color="tab:blue", label="CTF (paper's synthesis)")
        ny = budget.nyquist_cy_per_mm[d]
        ax.axvline(ny, color="gray", lw=1)
        ax.text(ny, 0.72, f"Nyquist {ny:.1f} ", color="0.35", rotation=90, ha="right", va="center")
        ax.set_xlim(0, f[-1])
        ax.set_ylim(0, 1.08)
        ax.set_xlabel("focal-plane spatial frequency (cycles/mm)")
        ax.set_title(f"{d.upper()} ({'along-track, f_y' if d == 'alt' else 'across-track, f_x'})")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("modulation")
    handles: dict[str, Artist] = {}
    for ax in axes:  # one legend for both panels, below them (the ACT panel lacks the smear)
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
    labels = list(handles)
    fig.legend([handles[k] for k in labels], labels, loc="lower center", ncol=3)
    if title:
        fig.suptitle(title)
    top = (0.02 * fig.get_figheight() + text_height_in("figure.titlesize") if title else 0.0) + title_band_in()
    bottom = legend_height_in(-(-len(labels) // 3)) + axis_band_in()
    place_grid(fig, [axes], top=top, bottom=bottom, hgap=0.2)  # the y axis shared: labelled on the left only
    save_figure(fig, path, dpi=100)


@with_rc(8)
def plot_square_wave(
    x_m: np.ndarray,
    square: np.ndarray,
    degraded: np.ndarray,
    path: str | Path,
    *,
    period_m: float,
    note: str = "",
) -> None:
    """The paper's Figure 3(b): truncated Fourier series of a bar pattern and its MTF-degraded version."""
    fig = Figure(figsize=(8, 4.6), dpi=100)  # a fixed layout in inches, placed below (_style.place_grid)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.plot(x_m, square, "k-", label="input square wave (truncated Fourier series)")
    ax.plot(x_m, degraded, "b--", label="degraded by the system MTF")
    ax.set_xlabel("ground position (m)")
    ax.set_ylabel("relative reflectance")
    ax.set_title(f"Square wave of ground period {period_m:g} m{(' - ' + note) if note else ''}")
    ax.grid(alpha=0.3)
    fig.legend(loc="lower center", ncol=2)
    place_grid(fig, [[ax]], top=title_band_in(), bottom=legend_height_in(1) + axis_band_in())
    save_figure(fig, path, dpi=100)
