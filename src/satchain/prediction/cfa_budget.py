"""The budget of a Bayer colour camera (issue 32 point 4): each colour plane's MTF on its own sampling grid and
where it aliases, as the block ``cfa`` of :func:`satchain.prediction.budget.budget_results` (``satchain budget``,
text and ``--json``; ``satchain.budget(system).cfa``).

Each colour's photosites sample the image formed through that colour's spectral response
(:func:`satchain.config.sections_cfa.colour_system`: the optics' wavelengths from the response, the same pixel
aperture and motion) on a lattice of their own (:mod:`satchain.tf.cfa`): red and blue every other row and
column (pitch 2 px, Nyquist 1/(4p) along the axes), green the quincunx (pitch sqrt(2) px along the diagonals,
Nyquist 1/(2p) along the axes and 1/(2 sqrt(2) p) along the diagonals). Per plane the block gives the Nyquist
frequency along ACT, ALT and the diagonal with the plane's pre-sampling MTF there, the MTF at its own grid's
Nyquist (where a slanted edge measured on the plane's own grid reads "MTF at Nyquist"), the nearest points of its
reciprocal lattice (an input frequency ``f`` reappears at ``f - g``), along each direction the frequency that
aliases back to zero (the plane's sampling frequency along it) and the fraction of the plane's MTF volume that
lies beyond its Nyquist.

Frequencies are cycles per pixel of the full array (``cy/px``) unless a name says otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from satchain.config.sections_cfa import CFA_COLOURS, colour_system
from satchain.errors import ConfigError
from satchain.tf.budget import SystemOTF
from satchain.tf.cfa import (
    alias_frequencies_cy_per_px,
    aliased_fraction,
    cfa_sites,
    grid_nyquist_cy_per_px,
    nyquist_cy_per_px,
    plane_lattice,
    plane_mtf,
)
from satchain.units import MM_PER_M

__all__ = ["CFABudget", "CFAPlaneBudget", "SAMPLING", "alias_along_cy_per_px", "cfa_budget", "responses_source"]

#: How each colour plane samples (the words the budget and the run print).
SAMPLING = {
    "red": "every other row and column (2 px grid)",
    "green": "quincunx (sqrt(2) px grid along the diagonals)",
    "blue": "every other row and column (2 px grid)",
}
#: The directions of the block, as angles from +x (ACT) towards +y (ALT), degrees.
DIRECTIONS_DEG = {"act": 0.0, "alt": 90.0, "diagonal": 45.0}
_DEFAULT_SOURCE = ("packaged default: Nikon D5100 spectral sensitivities measured at NPL (Darrodi et al., JOSA A "
                   "32(3) 381, 2015)")  # fmt: skip


def responses_source(detector: Any) -> dict[str, str]:
    """Where each colour's spectral response comes from: the system file (a Gaussian or a table) or the packaged
    default (:func:`satchain.config.sections_cfa.default_cfa_response`).

    Examples
    --------
    >>> from satchain import load_preset
    >>> responses_source(load_preset("ankarasat3").replace({"detector.cfa": "RGGB"}).detector)["red"][:16]
    'packaged default'
    """
    out = {}
    for colour in CFA_COLOURS:
        r = getattr(getattr(detector, "cfa_responses", None), colour, None)
        if r is None:
            out[colour] = _DEFAULT_SOURCE
        elif r.center_m is not None:
            out[colour] = f"system file: Gaussian, centre {r.center_m * 1e9:.1f} nm, FWHM {r.fwhm_m * 1e9:.1f} nm"
        else:
            out[colour] = f"system file: a table of {len(r.wavelengths_m)} wavelengths"
    return out


def alias_along_cy_per_px(pattern: str, colour: str, direction_deg: float) -> float:
    """The frequency along a direction that the plane's samples alias back to (nearly) zero: ``g . u`` for the
    nearest reciprocal-lattice point ``g`` to the ray ``f u`` (``u`` the direction; the smallest ``g . u`` among
    those equally near). Along a lattice vector it is the plane's sampling frequency, twice its Nyquist: red and
    blue 0.5 cy/px along the axes, green 1 cy/px along the axes and 0.707 along the diagonals.

    Examples
    --------
    >>> alias_along_cy_per_px("RGGB", "red", 0.0), alias_along_cy_per_px("RGGB", "green", 0.0)
    (0.5, 1.0)
    >>> round(alias_along_cy_per_px("RGGB", "green", 45.0), 4)
    0.7071
    """
    a = math.radians(direction_deg)
    u = np.array([math.cos(a), math.sin(a)])
    g = alias_frequencies_cy_per_px(pattern, colour, f_max_cy_per_px=2.0)
    gu = g @ u
    ahead = gu > 1e-12
    g, gu = g[ahead], gu[ahead]
    perp = np.round(np.hypot(*(g - gu[:, None] * u).T), 12)
    best = np.lexsort((gu, perp))[0]
    return float(gu[best])


def _mtf50(otf, pitch_x_m: float, pitch_y_m: float, direction_deg: float) -> float | None:
    f = np.linspace(0.0, 1.5, 1501)
    m = plane_mtf(otf, f, pitch_x_m=pitch_x_m, pitch_y_m=pitch_y_m, direction_deg=direction_deg)
    below = np.nonzero(m < 0.5)[0]
    if below.size == 0:
        return None
    k = int(below[0])
    return float(f[k - 1] + (f[k] - f[k - 1]) * (m[k - 1] - 0.5) / (m[k - 1] - m[k]))


def _aliased_fraction(otf, system, pattern: str, colour: str) -> float:
    """The fraction of the plane's 2-D MTF volume beyond its first Brillouin zone, on a uniform grid out to the
    colour's optical cutoff (cy/px; the system MTF is 0 beyond it)."""
    det = system.detector
    cut_mm = float(np.max(system.optical_cutoff_cy_per_mm))
    extent = cut_mm * max(det.pitch_x_m, det.pitch_y_m) * MM_PER_M
    f = np.linspace(-extent, extent, 161)
    fx, fy = np.meshgrid(f, f)
    mtf = np.abs(np.asarray(otf(fx / (det.pitch_x_m * MM_PER_M), fy / (det.pitch_y_m * MM_PER_M))))
    return aliased_fraction(fx, fy, mtf, pattern, colour)


def _plane(system, pattern: str, colour: str) -> dict[str, Any]:
    det = system.detector
    s = colour_system(system, colour)
    otf = SystemOTF(s)
    lat = plane_lattice(pattern, colour)
    px, py = det.pitch_x_m, det.pitch_y_m
    g = alias_frequencies_cy_per_px(pattern, colour, f_max_cy_per_px=1.0)
    r = np.hypot(g[:, 0], g[:, 1])
    first = g[np.isclose(r, r.min(), rtol=1e-9)]
    ny = {d: nyquist_cy_per_px(pattern, colour, direction_deg=a) for d, a in DIRECTIONS_DEG.items()}
    fg = grid_nyquist_cy_per_px(colour)

    def at(f: float, a: float) -> float:
        return float(plane_mtf(otf, f, pitch_x_m=px, pitch_y_m=py, direction_deg=a))

    return {
        "sampling": SAMPLING[colour],
        "sites_rc": [list(v) for v in cfa_sites(pattern, colour)],
        "sites_per_pixel": lat.sites_per_pixel,
        "lattice_pitch_px": lat.pitch_px,
        "effective_wavelength_m": s.optics.effective_wavelength_m,
        "nyquist_cy_per_px": ny,
        "nyquist_cy_per_mm": {"act": ny["act"] / (px * MM_PER_M), "alt": ny["alt"] / (py * MM_PER_M)},
        "mtf_at_nyquist": {d: at(ny[d], a) for d, a in DIRECTIONS_DEG.items()},
        "grid_nyquist_cy_per_px": fg,
        "mtf_at_grid_nyquist": {d: at(fg, DIRECTIONS_DEG[d]) for d in ("act", "alt")},
        "alias_cy_per_px": {d: alias_along_cy_per_px(pattern, colour, a) for d, a in DIRECTIONS_DEG.items()},
        "first_alias_points_cy_per_px": (first + 0.0).tolist(),
        "aliased_fraction": _aliased_fraction(otf, s, pattern, colour),
        "mtf50_cy_per_px": {d: _mtf50(otf, px, py, DIRECTIONS_DEG[d]) for d in ("act", "alt")},
    }


def cfa_budget(system: Any) -> dict[str, Any]:
    """Each colour plane of ``system``'s colour filter array on its own sampling grid (JSON-ready; see the
    module's description): ``pattern``, ``responses`` (each colour's source), ``planes`` (colour -> its figures)
    and ``notes``.

    Examples
    --------
    >>> from satchain import load_preset
    >>> b = cfa_budget(load_preset("ankarasat3").replace({"detector.cfa": "RGGB"}))
    >>> b["planes"]["red"]["nyquist_cy_per_px"]["act"], b["planes"]["green"]["nyquist_cy_per_px"]["act"]
    (0.25, 0.5)
    >>> b["planes"]["red"]["mtf_at_nyquist"]["act"] > b["planes"]["green"]["mtf_at_nyquist"]["act"]
    True
    """
    pattern = system.detector.cfa
    if pattern is None:
        raise ConfigError("system.detector.cfa = None: the colour planes' budget needs a colour filter array")
    return {
        "pattern": pattern,
        "responses": responses_source(system.detector),
        "planes": {c: _plane(system, pattern, c) for c in CFA_COLOURS},
        "notes": (
            "frequencies in cy/px of the full array (cy/mm = cy/px / pitch in mm); each plane's MTF is the system "
            "MTF through its colour's spectral response (same pixel aperture and motion), evaluated at the plane's "
            "own Nyquist along ACT, ALT and the diagonal; grid Nyquist: 1/(2 x the plane's lattice pitch), where a "
            "slanted edge measured on the plane's own grid reads MTF at Nyquist; alias_cy_per_px: the frequency "
            "along each direction that the plane's samples alias back to zero (its sampling frequency); "
            "first_alias_points: the nearest reciprocal-lattice points g (an input f reappears at f - g); "
            "aliased_fraction: the part of the plane's 2-D MTF volume beyond its Nyquist"
        ),
    }


@dataclass(frozen=True)
class CFAPlaneBudget:
    """One colour plane's budget, typed (:func:`cfa_budget`'s ``planes[colour]``): ``nyquist_cy_per_px``,
    ``mtf_at_nyquist`` and ``alias_cy_per_px`` map ``act``, ``alt`` and ``diagonal`` to their values."""

    colour: str
    sampling: str
    effective_wavelength_m: float
    nyquist_cy_per_px: Mapping[str, float]
    mtf_at_nyquist: Mapping[str, float]
    grid_nyquist_cy_per_px: float
    mtf_at_grid_nyquist_act: float
    mtf_at_grid_nyquist_alt: float
    alias_cy_per_px: Mapping[str, float]
    aliased_fraction: float


@dataclass(frozen=True)
class CFABudget:
    """A colour filter array's budget, typed (``satchain.budget(system).cfa``): ``pattern``, ``responses``
    (colour -> source) and ``planes`` (colour -> :class:`CFAPlaneBudget`)."""

    pattern: str
    responses: Mapping[str, str]
    planes: Mapping[str, CFAPlaneBudget]

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> CFABudget:
        planes = {}
        for c, p in d["planes"].items():
            planes[c] = CFAPlaneBudget(
                colour=c,
                sampling=str(p["sampling"]),
                effective_wavelength_m=float(p["effective_wavelength_m"]),
                nyquist_cy_per_px=dict(p["nyquist_cy_per_px"]),
                mtf_at_nyquist=dict(p["mtf_at_nyquist"]),
                grid_nyquist_cy_per_px=float(p["grid_nyquist_cy_per_px"]),
                mtf_at_grid_nyquist_act=float(p["mtf_at_grid_nyquist"]["act"]),
                mtf_at_grid_nyquist_alt=float(p["mtf_at_grid_nyquist"]["alt"]),
                alias_cy_per_px=dict(p["alias_cy_per_px"]),
                aliased_fraction=float(p["aliased_fraction"]),
            )
        return cls(str(d["pattern"]), dict(d["responses"]), planes)
