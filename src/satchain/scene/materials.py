"""Spectral materials: a packaged library of measured reflectance spectra, PROSAIL vegetation, band averages.

A :class:`Material` is a reflectance spectrum (wavelengths in metres, reflectance in [0, 1]) with its source.
The library (:func:`materials`, :func:`material`) holds measured spectra of the USGS Spectral Library Version 7
(Kokaly et al. 2017, public domain), packaged as CSV files under ``satchain/data/materials/`` (350-2500 nm at
5 nm; each file's header names its record, instrument and licence; see ``data/README.md``), and green vegetation
computed with PROSAIL (PROSPECT-5 + 4SAIL, Jacquemoud et al. 2009) by :func:`vegetation`, whose leaf and canopy
parameters a user may set. Nothing is downloaded at run time.

:func:`band_reflectance` turns a material (or a grey value, a flat spectrum) into the reflectance a band sees:
the response-weighted mean ``integral R(lam) S(lam) dlam / integral S(lam) dlam``.

Examples
--------
>>> "asphalt" in materials()
True
>>> lam = np.linspace(600e-9, 700e-9, 101)
>>> band_reflectance(0.3, lam, np.ones_like(lam))
0.3
"""

from __future__ import annotations

import dataclasses
import math
import os
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from satchain._validate import check_range
from satchain.errors import ConfigError, SatchainIOError

__all__ = [
    "DEFAULT_BAND_M",
    "Material",
    "PROSAIL_DEFAULTS",
    "band_extent_m",
    "band_reflectance",
    "default_grey",
    "material",
    "materials",
    "read_spectrum",
    "vegetation",
]

#: The packaged measured spectra (file stems under ``satchain/data/materials/``).
_PACKAGED: tuple[str, ...] = (
    "asphalt",
    "black_paint",
    "concrete",
    "dry_grass",
    "galvanized_metal",
    "red_brick",
    "roof_shingle",
    "water",
    "white_paint",
    "white_reference",
)
#: Library names computed with PROSAIL at :data:`PROSAIL_DEFAULTS`.
_COMPUTED: tuple[str, ...] = ("green_vegetation",)

#: The band a scene renders a material in when no band is given: a flat response over 450-900 nm (the reference
#: camera's panchromatic band, presets/ankarasat3.toml ``band_m``).
DEFAULT_BAND_M: tuple[float, float] = (450e-9, 900e-9)

#: PROSAIL's leaf (PROSPECT-5) and canopy (4SAIL) parameters, their defaults and allowed ranges: a dense green
#: canopy of typical leaves (the values of Jacquemoud et al. 2009, Table 2 mid-range, and the prosail package's
#: example), a spherical leaf-angle distribution (mean 57.3 deg), dry soil, sun 30 deg from the zenith, nadir view.
PROSAIL_DEFAULTS: dict[str, tuple[float, float, float, str]] = {
    # name: (default, lo, hi, meaning)
    "n": (1.5, 1.0, 3.0, "leaf structure parameter N (number of layers)"),
    "cab_ug_per_cm2": (40.0, 0.0, 150.0, "chlorophyll a+b content Cab (ug/cm2)"),
    "car_ug_per_cm2": (8.0, 0.0, 50.0, "carotenoid content Car (ug/cm2)"),
    "cbrown": (0.0, 0.0, 1.0, "brown pigment fraction Cbrown"),
    "cw_cm": (0.01, 0.0, 0.1, "equivalent water thickness Cw (cm, = g/cm2)"),
    "cm_g_per_cm2": (0.009, 0.0, 0.05, "dry matter content Cm (g/cm2)"),
    "lai": (3.0, 0.0, 10.0, "leaf area index LAI"),
    "leaf_angle_deg": (57.3, 0.0, 90.0, "average leaf inclination angle (ellipsoidal distribution)"),
    "hotspot": (0.01, 0.0, 1.0, "hot-spot parameter (leaf size / canopy height)"),
    "soil_brightness": (1.0, 0.0, 2.0, "soil brightness factor (scales the soil spectrum)"),
    "soil_dry_fraction": (1.0, 0.0, 1.0, "soil moisture mix: 1 = the dry soil spectrum, 0 = the wet one"),
    "sun_zenith_deg": (30.0, 0.0, 85.0, "solar zenith angle"),
    "view_zenith_deg": (0.0, 0.0, 85.0, "view zenith angle"),
    "relative_azimuth_deg": (0.0, 0.0, 360.0, "relative azimuth between sun and view"),
}

#: A response sample at or below this fraction of its peak lies outside the band (for the range check).
_BAND_EDGE_FRACTION = 1e-6


@dataclasses.dataclass(frozen=True, eq=False)
class Material:
    """A reflectance spectrum with its source.

    ``wavelengths_m`` strictly increasing (at least two samples); ``reflectance`` in [0, 1], same length; both are
    stored as read-only float arrays. ``source`` names where the data come from (library, record, licence).

    Examples
    --------
    >>> m = Material("grey", np.array([400e-9, 1000e-9]), np.array([0.2, 0.2]), source="a flat example")
    >>> m.range_m
    (4e-07, 1e-06)
    """

    name: str
    wavelengths_m: np.ndarray
    reflectance: np.ndarray
    source: str

    def __post_init__(self):
        where = f"material {self.name!r}"
        w = np.array(self.wavelengths_m, dtype=float).ravel()
        r = np.array(self.reflectance, dtype=float).ravel()
        if w.size < 2 or w.size != r.size:
            raise ConfigError(
                f"{where}: wavelengths_m ({w.size}) and reflectance ({r.size}) must have the same length, >= 2"
            )
        if not (np.all(np.isfinite(w)) and np.all(np.isfinite(r))):
            raise ConfigError(f"{where}: wavelengths_m and reflectance must be finite")
        _check_increasing(f"{where}.wavelengths_m", w)
        if w[0] <= 0:
            raise ConfigError(f"{where}.wavelengths_m: must be > 0 (metres), got {float(w[0])!r}")
        if r.min() < 0 or r.max() > 1:
            raise ConfigError(f"{where}.reflectance: must be in [0, 1], got [{r.min():.4g}, {r.max():.4g}]")
        w.setflags(write=False)
        r.setflags(write=False)
        object.__setattr__(self, "wavelengths_m", w)
        object.__setattr__(self, "reflectance", r)

    @property
    def range_m(self) -> tuple[float, float]:
        """(shortest, longest) wavelength of the spectrum (m)."""
        return (float(self.wavelengths_m[0]), float(self.wavelengths_m[-1]))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Material):
            return NotImplemented
        return (
            self.name == other.name
            and self.source == other.source
            and np.array_equal(self.wavelengths_m, other.wavelengths_m)
            and np.array_equal(self.reflectance, other.reflectance)
        )

    def __hash__(self) -> int:
        return hash((self.name, self.source, self.wavelengths_m.size))

    def __repr__(self) -> str:
        lo, hi = self.range_m
        return f"Material({self.name!r}, {lo * 1e9:.0f}-{hi * 1e9:.0f} nm, {self.wavelengths_m.size} samples)"


def _check_increasing(name: str, w: np.ndarray) -> None:
    d = np.diff(w)
    if np.any(d <= 0):
        i = int(np.argmax(d <= 0))
        raise ConfigError(
            f"{name}: must be strictly increasing; sample {i + 1} ({float(w[i + 1])!r}) follows {float(w[i])!r}"
        )


def materials() -> list[str]:
    """The library's material names, sorted.

    Examples
    --------
    >>> materials()[:3]
    ['asphalt', 'black_paint', 'concrete']
    """
    return sorted(_PACKAGED + _COMPUTED)


def material(name: str) -> Material:
    """The library material ``name`` (see :func:`materials`); an unknown name is a ConfigError listing the library.

    Examples
    --------
    >>> m = material("water")
    >>> m.range_m
    (3.5e-07, 2.5e-06)
    """
    if name in _PACKAGED:
        return _read_packaged(name)
    if name == "green_vegetation":
        return vegetation()
    raise ConfigError(f"material = {name!r}: not in the library; known: {', '.join(materials())}")


def _read_packaged(name: str) -> Material:
    ref = resources.files("satchain") / "data" / "materials" / f"{name}.csv"
    return _parse_spectrum(ref.read_text(encoding="utf-8"), name=name, where=f"data/materials/{name}.csv")


def read_spectrum(path: str | os.PathLike, *, name: str | None = None) -> Material:
    """A reflectance spectrum from a CSV file: ``wavelength_nm,reflectance`` rows (a header row and ``#`` comment
    lines allowed; the comments become the material's source), wavelengths strictly increasing.

    Examples
    --------
    >>> import tempfile
    >>> f = Path(tempfile.mkdtemp()) / "paint.csv"
    >>> _ = f.write_text("# my paint, measured 2024\\nwavelength_nm,reflectance\\n400,0.5\\n1000,0.6\\n")
    >>> read_spectrum(f).range_m
    (4e-07, 1e-06)
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"spectrum_file = {str(p)!r}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SatchainIOError(f"spectrum_file = {str(p)!r}: cannot read: {exc}") from None
    return _parse_spectrum(text, name=name or p.stem, where=str(p))


def _parse_spectrum(text: str, *, name: str, where: str) -> Material:
    comments, rows = [], []
    for k, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            comments.append(s.lstrip("#").strip())
            continue
        parts = [t.strip() for t in s.replace(";", ",").split(",")]
        try:
            rows.append((float(parts[0]), float(parts[1])))
        except (ValueError, IndexError):
            if rows:  # a header is allowed only before the data
                raise ConfigError(
                    f"spectrum file {where!r} line {k}: {s!r} is not 'wavelength_nm,reflectance'"
                ) from None
    if len(rows) < 2:
        raise ConfigError(f"spectrum file {where!r}: needs at least two 'wavelength_nm,reflectance' rows")
    arr = np.asarray(rows, dtype=float)
    _check_increasing(f"spectrum file {where!r} wavelength_nm", arr[:, 0])
    source = " ".join(c for c in comments if c) or f"spectrum file {where}"
    return Material(name, arr[:, 0] / 1e9, arr[:, 1], source=source)


def vegetation(**params: float) -> Material:
    """A green canopy's reflectance computed with PROSAIL (PROSPECT-5 leaf + 4SAIL canopy; Jacquemoud et al.
    2009, *Remote Sens. Environ.* 113, S56-S66) through the ``prosail`` package (J. Gomez-Dans), 400-2500 nm at
    1 nm, the directional (sun-to-view) reflectance factor.

    Parameters (keyword only; defaults and ranges in :data:`PROSAIL_DEFAULTS`): ``n``, ``cab_ug_per_cm2``,
    ``car_ug_per_cm2``, ``cbrown``, ``cw_cm``, ``cm_g_per_cm2``, ``lai``, ``leaf_angle_deg``, ``hotspot``,
    ``soil_brightness``, ``soil_dry_fraction`` (the package's dry and wet soil spectra), ``sun_zenith_deg``,
    ``view_zenith_deg``, ``relative_azimuth_deg``.

    Examples
    --------
    >>> v = vegetation(lai=5.0)
    >>> v.name, v.range_m
    ('vegetation(lai=5)', (4e-07, 2.5e-06))
    """
    unknown = sorted(set(params) - set(PROSAIL_DEFAULTS))
    if unknown:
        raise ConfigError(f"vegetation: unknown parameter(s) {unknown}; allowed: {sorted(PROSAIL_DEFAULTS)}")
    p = {}
    for key, (default, lo, hi, _) in PROSAIL_DEFAULTS.items():
        p[key] = check_range(f"vegetation.{key}", params.get(key, default), lo, hi)
    if p["cw_cm"] == 0.0 and p["cm_g_per_cm2"] == 0.0:
        raise ConfigError("vegetation.cw_cm = 0 and cm_g_per_cm2 = 0: a leaf needs water or dry matter")
    import prosail  # type: ignore[import-untyped]

    rho = prosail.run_prosail(
        p["n"], p["cab_ug_per_cm2"], p["car_ug_per_cm2"], p["cbrown"], p["cw_cm"], p["cm_g_per_cm2"],
        p["lai"], p["leaf_angle_deg"], p["hotspot"], p["sun_zenith_deg"], p["view_zenith_deg"],
        p["relative_azimuth_deg"], typelidf=2, rsoil=p["soil_brightness"], psoil=p["soil_dry_fraction"],
    )  # fmt: skip
    wavelengths_m = np.arange(400, 2501, dtype=float) / 1e9
    changed = {k: v for k, v in p.items() if v != PROSAIL_DEFAULTS[k][0]}
    name = "vegetation(" + ", ".join(f"{k}={v:g}" for k, v in changed.items()) + ")" if changed else "green_vegetation"
    described = ", ".join(f"{k}={v:g}" for k, v in p.items())
    source = (
        "PROSAIL (PROSPECT-5 + 4SAIL; Jacquemoud et al. 2009, Remote Sens. Environ. 113, S56-S66) computed with "
        f"the prosail package (https://github.com/jgomezdans/prosail), directional reflectance factor; {described}"
    )
    return Material(name, wavelengths_m, np.clip(np.asarray(rho, dtype=float), 0.0, 1.0), source=source)


def _check_response(wavelengths_m: Any, response: Any) -> tuple[np.ndarray, np.ndarray]:
    w = np.asarray(wavelengths_m, dtype=float).ravel()
    s = np.asarray(response, dtype=float).ravel()
    if w.size < 2 or w.size != s.size:
        raise ConfigError(
            f"band response: wavelengths_m ({w.size}) and response ({s.size}) must have the same length, >= 2"
        )
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(s))):
        raise ConfigError("band response: wavelengths_m and response must be finite")
    _check_increasing("band response wavelengths_m", w)
    if s.min() < 0:
        raise ConfigError(f"band response: must be >= 0, got {s.min():.4g}")
    if s.max() <= 0:
        raise ConfigError("band response: is zero everywhere; a band needs a positive response somewhere")
    return w, s


def band_extent_m(wavelengths_m: Any, response: Any) -> tuple[float, float]:
    """(shortest, longest) wavelength where the response exceeds 1e-6 of its peak (the band's extent, m)."""
    w, s = _check_response(wavelengths_m, response)
    inside = np.flatnonzero(s > _BAND_EDGE_FRACTION * s.max())
    return (float(w[inside[0]]), float(w[inside[-1]]))


#: the largest share of a band's response that may lie outside a material's range (its end value taken there: a
#: measured response's noise floor, e.g. a camera's 0.2 % at 380-395 nm against PROSAIL's 400 nm start)
OUTSIDE_WEIGHT = 1e-3


def _weight_outside(w: np.ndarray, s: np.ndarray, lo: float, hi: float) -> float:
    """The share of ``integral S`` (piecewise linear) below ``lo`` or above ``hi``."""
    grid = np.union1d(w, [x for x in (lo, hi) if w[0] < x < w[-1]])
    sg = np.interp(grid, w, s)
    seg = np.diff(grid) * (sg[:-1] + sg[1:]) / 2.0
    mid = (grid[:-1] + grid[1:]) / 2.0
    total = float(seg.sum())
    return float(seg[(mid < lo) | (mid > hi)].sum()) / total if total > 0 else 0.0


def band_reflectance(material_or_value: Material | float, wavelengths_m: Any, response: Any) -> float:
    """The reflectance a band sees: ``integral R(lam) S(lam) dlam / integral S(lam) dlam``.

    ``response`` S is sampled at ``wavelengths_m`` (strictly increasing, >= 0, any scale) and taken as piecewise
    linear between samples, as is the material's spectrum R; the integral of their product is exact on the union
    of both sample grids. A number is a grey (flat) spectrum and is returned exactly. A band with more than
    :data:`OUTSIDE_WEIGHT` of its response outside the material's wavelength range is a ConfigError naming both
    ranges (below that share the spectrum's end value is taken there).

    Examples
    --------
    >>> lam = np.linspace(500e-9, 700e-9, 201)
    >>> flat = Material("flat", np.array([350e-9, 2500e-9]), np.array([0.4, 0.4]), source="example")
    >>> round(band_reflectance(flat, lam, np.exp(-0.5 * ((lam - 600e-9) / 30e-9) ** 2)), 12)
    0.4
    """
    w, s = _check_response(wavelengths_m, response)
    if not isinstance(material_or_value, Material):
        value = check_range("reflectance", material_or_value, 0.0, 1.0)
        return value
    m = material_or_value
    lo, hi = m.range_m
    b_lo, b_hi = band_extent_m(w, s)
    outside = _weight_outside(w, s, lo, hi)
    if outside > OUTSIDE_WEIGHT:
        raise ConfigError(
            f"band {b_lo * 1e9:.1f}-{b_hi * 1e9:.1f} nm reaches outside material {m.name!r}'s "
            f"{lo * 1e9:.1f}-{hi * 1e9:.1f} nm ({outside:.2%} of its response; at most {OUTSIDE_WEIGHT:.1%} may lie "
            "outside, where the spectrum's end value is taken)"
        )
    grid = np.union1d(w, m.wavelengths_m[(m.wavelengths_m > w[0]) & (m.wavelengths_m < w[-1])])
    sg = np.interp(grid, w, s)
    rg = np.interp(grid, m.wavelengths_m, m.reflectance)  # constant beyond the range: only where S ~ 0
    h = np.diff(grid)
    s0, s1, r0, r1 = sg[:-1], sg[1:], rg[:-1], rg[1:]
    num = float(np.sum(h * (2 * r0 * s0 + r0 * s1 + r1 * s0 + 2 * r1 * s1))) / 6.0
    den = float(np.sum(h * (s0 + s1))) / 2.0
    out = num / den
    return min(1.0, max(0.0, out)) if math.isfinite(out) else out


def default_grey(m: Material) -> float:
    """``m``'s reflectance over :data:`DEFAULT_BAND_M` with a flat response (a scene's grey value for it)."""
    lo, hi = DEFAULT_BAND_M
    w = np.linspace(lo, hi, 451)
    return band_reflectance(m, w, np.ones_like(w))
