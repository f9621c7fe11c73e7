"""The paper's Figure 2: spectral radiance of the surface and at the top of the atmosphere."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from satchain.radiometry import RadiometryResult, spectral_per_m_to_per_um
from satchain.report._save import save_figure
from satchain.report._style import axis_band_in, place_grid, title_band_in
from satchain.report.compare_plots import with_rc

__all__ = ["plot_spectral_radiance"]


@with_rc(8)
def plot_spectral_radiance(
    result: RadiometryResult, path: str | Path, *, wavelength_range_m: tuple[float, float] = (2.8e-7, 2.5e-6)
) -> None:
    """Spectral radiance (W m^-2 sr^-1 µm^-1) vs wavelength (µm): the surface-leaving radiance and the
    radiance at the top of the atmosphere, with the sensor band shaded -- the equivalent of the reference
    paper's Figure 2 (albedo 0.2, 23 % atmospheric absorption). Written atomically (PNG, SVG or PDF by
    the suffix of ``path``).
    """
    lam = result.wavelength_m
    keep = (lam >= wavelength_range_m[0]) & (lam <= wavelength_range_m[1])
    x_um = lam[keep] * 1e6
    fig = Figure(figsize=(8, 5), dpi=100)  # a fixed layout in inches, placed below (_style.place_grid)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.plot(
        x_um,
        spectral_per_m_to_per_um(result.radiance_surface_w_per_m2_sr_per_m[keep]),
        color="tab:green",
        lw=1.0,
        label=f"surface (albedo {result.reflectance:g}, T_down {result.transmission_down:.2f})",
    )
    ax.plot(
        x_um,
        spectral_per_m_to_per_um(result.radiance_toa_w_per_m2_sr_per_m[keep]),
        color="tab:blue",
        lw=1.0,
        label=f"top of atmosphere (T_up {result.transmission_up:.2f})",
    )
    lo, hi = (b * 1e6 for b in result.band_m)
    ax.axvspan(lo, hi, color="0.85", zorder=0, label=f"band {lo:.2f}-{hi:.2f} µm")
    ax.set_xlim(float(np.min(x_um)), float(np.max(x_um)))
    ax.set_ylim(bottom=0)
    ax.set_xlabel("wavelength (µm)")
    ax.set_ylabel("spectral radiance (W m$^{-2}$ sr$^{-1}$ µm$^{-1}$)")
    ax.set_title(
        f"Spectral radiance, sun zenith {result.sun_zenith_deg:g} deg, {result.solar_spectrum}\n"
        f"in band: surface {result.radiance_surface_band_w_per_m2_sr:.1f}, "
        f"TOA {result.radiance_toa_band_w_per_m2_sr:.1f} W m$^{{-2}}$ sr$^{{-1}}$"
    )
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right")  # a fixed corner ("best" searches every point): the spectrum peaks in the visible
    place_grid(fig, [[ax]], top=title_band_in(2), bottom=axis_band_in())
    save_figure(fig, path, dpi=100)
