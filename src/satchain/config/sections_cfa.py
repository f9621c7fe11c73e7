"""The colour filter array keys of ``[detector]``: the spectral response of each colour's filter on silicon
(``[detector.cfa_responses.red]``, ``.green``, ``.blue``), a Gaussian or a table, and the packaged default responses
(``data/cfa/nikon_d5100_npl.csv``, see ``data/README.md``) used for a colour that has none, so that
``cfa = "RGGB"`` alone describes a complete colour camera. :class:`satchain.config.sections.Detector` holds them."""

from __future__ import annotations

import math
from functools import cache
from importlib import resources
from typing import Any, Literal

import numpy as np
from pydantic import Field, model_validator

from satchain.config._base import _Frozen, schema_bounds
from satchain.config.response import (
    Response,
    SuperGaussianResponse,
    TabulatedResponse,
    response_quadrature,
    response_table,
)
from satchain.errors import ConfigError

__all__ = [
    "CFA_COLOURS",
    "CFA_PATTERNS",
    "CFAResponse",
    "CFAResponses",
    "cfa_response",
    "colour_system",
    "default_cfa_response",
]

#: The 2x2 Bayer cells satchain knows, read row by row from the first pixel (row 0, column 0).
CFA_PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")
CFA_COLOURS = ("red", "green", "blue")
_DEFAULT_TABLE = "nikon_d5100_npl.csv"
_FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))


class CFAResponse(_Frozen):
    """The relative spectral response of one colour's photosites (filter transmission x silicon QE), peak 1:
    a Gaussian (``center_m``, ``fwhm_m``) or a table (``wavelengths_m``, ``values``; linear between its
    points, 0 outside), not both.

    Examples
    --------
    >>> round(float(CFAResponse(center_m=6.0e-7, fwhm_m=1.0e-7).at(6.5e-7)), 6)
    0.5
    """

    center_m: float | None = Field(
        default=None, ge=1e-8, le=1e-4, description="centre wavelength of a Gaussian response, m (with fwhm_m)"
    )
    fwhm_m: float | None = Field(
        default=None, gt=0, le=1e-4, description="full width at half maximum of a Gaussian response, m"
    )
    wavelengths_m: tuple[float, ...] | None = Field(
        default=None,
        description="wavelengths of a response table, m: >= 2, strictly increasing, each in [1e-08, 0.0001] m",
        json_schema_extra=schema_bounds(items={"minimum": 1e-8, "maximum": 1e-4}),
    )
    values: tuple[float, ...] | None = Field(
        default=None,
        description="relative response at each of wavelengths_m (dimensionless, >= 0, positive somewhere)",
        json_schema_extra=schema_bounds(items={"minimum": 0}),
    )

    @model_validator(mode="after")
    def _one_kind(self) -> CFAResponse:
        gauss = (self.center_m is not None, self.fwhm_m is not None)
        table = (self.wavelengths_m is not None, self.values is not None)
        if any(gauss) and any(table):
            raise ValueError("give a Gaussian (center_m, fwhm_m) or a table (wavelengths_m, values), not both")
        if any(gauss) and not all(gauss):
            raise ValueError("a Gaussian response needs both center_m and fwhm_m")
        if not any(gauss):
            w, r = self.wavelengths_m, self.values
            if w is None or r is None or len(w) != len(r) or len(w) < 2:
                raise ValueError(
                    "give center_m and fwhm_m, or wavelengths_m and values with the same number (>= 2) of "
                    f"values (got {None if w is None else len(w)} and {None if r is None else len(r)})"
                )
            if any(b <= a for a, b in zip(w[:-1], w[1:], strict=True)) or any(not 1e-8 <= x <= 1e-4 for x in w):
                raise ValueError(f"wavelengths_m = {list(w)!r}: must be strictly increasing, in [1e-08, 0.0001] m")
            if min(r) < 0 or max(r) <= 0:
                raise ValueError(f"values = {list(r)!r}: must be >= 0 and positive somewhere")
        return self

    def at(self, wavelength_m: Any) -> np.ndarray:
        """The relative response at the given wavelengths (m): the Gaussian, or the table interpolated
        linearly (0 outside it)."""
        lam = np.asarray(wavelength_m, dtype=float)
        if self.center_m is not None and self.fwhm_m is not None:
            sigma = self.fwhm_m / _FWHM_PER_SIGMA
            return np.exp(-0.5 * ((lam - self.center_m) / sigma) ** 2)
        assert self.wavelengths_m is not None and self.values is not None  # _one_kind
        return np.interp(lam, self.wavelengths_m, self.values, left=0.0, right=0.0)

    def as_response(self) -> Response:
        """The same response as :mod:`satchain.config.response` describes a band's (its support, quadrature)."""
        if self.center_m is not None and self.fwhm_m is not None:
            return SuperGaussianResponse(self.center_m, self.fwhm_m)
        assert self.wavelengths_m is not None and self.values is not None  # _one_kind
        return TabulatedResponse(self.wavelengths_m, self.values)


class CFAResponses(_Frozen):
    """The spectral responses of the three colours of a colour filter array; a colour left out takes the
    packaged default (:func:`default_cfa_response`)."""

    red: CFAResponse | None = Field(default=None, description="the red photosites' response; default: packaged")
    green: CFAResponse | None = Field(default=None, description="the green photosites' response; default: packaged")
    blue: CFAResponse | None = Field(default=None, description="the blue photosites' response; default: packaged")


@cache
def _default_table() -> tuple[tuple[float, ...], dict[str, tuple[float, ...]]]:
    text = (resources.files("satchain") / "data" / "cfa" / _DEFAULT_TABLE).read_text(encoding="utf-8")
    rows = [line.split(",") for line in text.splitlines()[1:] if line.strip()]
    lam = tuple(float(r[0]) * 1e-9 for r in rows)
    return lam, {c: tuple(float(r[i + 1]) for r in rows) for i, c in enumerate(CFA_COLOURS)}


def default_cfa_response(colour: str) -> CFAResponse:
    """The packaged response of ``colour`` ("red", "green" or "blue"): the Nikon D5100 camera's spectral
    sensitivities measured at the UK National Physical Laboratory (Darrodi, Finlayson, Goodman & Mackiewicz,
    "Reference data set for camera spectral sensitivity estimation", JOSA A 32(3), 381, 2015), 380-780 nm in
    5 nm steps, each colour normalised to its peak, as shipped by colour-science (``data/README.md``).

    Examples
    --------
    >>> r = default_cfa_response("red")
    >>> round(r.wavelengths_m[int(np.argmax(r.values))] * 1e9)
    595
    """
    if colour not in CFA_COLOURS:
        raise ConfigError(f"colour = {colour!r}: must be one of {', '.join(CFA_COLOURS)}")
    lam, values = _default_table()
    return CFAResponse(wavelengths_m=lam, values=values[colour])


def cfa_response(detector: Any, colour: str) -> CFAResponse:
    """The response of ``colour`` on ``detector`` (a :class:`~satchain.config.sections.Detector`): its
    ``cfa_responses`` entry, or the packaged default."""
    given = getattr(getattr(detector, "cfa_responses", None), colour, None) if colour in CFA_COLOURS else None
    return given if given is not None else default_cfa_response(colour)


def colour_system(system: Any, colour: str, *, nodes: int = 11) -> Any:
    """The system that forms ``colour``'s photosites of a colour filter array (as ``ImagingSystem.for_band``
    forms a band): the optics' wavelengths and weights are the quadrature of the colour's response (``nodes``
    centroid nodes, :func:`satchain.config.response.response_quadrature`), the radiometric band its support,
    the QE the detector's times the response over it. The same telescope, pixel and motion: its
    :class:`~satchain.tf.budget.SystemOTF` is the colour plane's pre-sampling MTF (``satchain.tf.cfa``).

    Examples
    --------
    >>> from satchain import load_preset
    >>> red = colour_system(load_preset("ankarasat3").replace({"detector.cfa": "RGGB"}), "red")
    >>> round(red.optics.effective_wavelength_m * 1e9)
    596
    """
    det = system.detector
    if det.cfa is None:
        raise ConfigError(f"colour = {colour!r}: detector.cfa is not set (a monochrome array has no colour planes)")
    r = cfa_response(det, colour).as_response()
    lam, w = response_quadrature(r, nodes)
    tab, resp = response_table(r)
    if isinstance(det.qe, tuple):
        k = np.asarray(det.qe_wavelengths_m)
        tab = np.union1d(tab, k[(k > tab[0]) & (k < tab[-1])])
        resp = r(tab)
    qe = np.clip(det.qe_at(tab) * resp, 0.0, 1.0)
    return system.replace(
        {
            "optics.wavelengths_m": tuple(float(x) for x in lam),
            "optics.wavelength_weights": tuple(float(x / w.sum()) for x in w),
            "radiometry.band_m": r.support_m,
            "detector.qe": tuple(float(x) for x in qe),
            "detector.qe_wavelengths_m": tuple(float(x) for x in tab),
        }
    )


CFAPattern = Literal["RGGB", "GRBG", "GBRG", "BGGR"]
