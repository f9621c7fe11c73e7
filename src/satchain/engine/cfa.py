"""Image formation through a Bayer colour filter array: the raw mosaic, demosaicing, and the false colour a
demosaiced image shows at a neutral edge.

:func:`mosaic` keeps, at each photosite, the value of its own colour's plane (the planes being the scene
already formed through the optics and the photosite aperture in each colour's spectral band);
:func:`demosaic` interpolates the missing colours with the colour-demosaicing library (bilinear; Malvar, He &
Cutler 2004; Menon, Andriani & Calvagno 2007); :func:`false_colour_amplitude` measures the chroma a
demosaiced image shows where the scene has none. The sampling each colour's plane sees is predicted by
:mod:`satchain.tf.cfa`.

Arrays are ``[row, col]`` (y ALT, x ACT); an RGB image is ``(rows, cols, 3)`` in the order red, green, blue,
as colour-demosaicing takes and returns it.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from satchain._validate import as_float_array, check_choice
from satchain.errors import InputError
from satchain.tf.cfa import CFA_COLOURS, CFA_PATTERNS, cfa_sites

__all__ = [
    "DEMOSAIC_METHODS",
    "FalseColour",
    "cfa_masks",
    "demosaic",
    "false_colour_amplitude",
    "luminance",
    "mosaic",
]

#: Demosaicing methods: satchain's name -> colour-demosaicing's function.
DEMOSAIC_METHODS = {
    "bilinear": "demosaicing_CFA_Bayer_bilinear",
    "malvar2004": "demosaicing_CFA_Bayer_Malvar2004",
    "menon2007": "demosaicing_CFA_Bayer_Menon2007",
}

_PAD_PX = 8  # mirror extension before demosaicing: wider than Menon 2007's 5-tap filters and its refining step

#: ITU-R BT.709-6 luma weights of linear red, green, blue.
REC709_LUMA = (0.2126, 0.7152, 0.0722)


def cfa_masks(shape: tuple[int, int], pattern: str, *, origin: tuple[int, int] = (0, 0)) -> dict[str, np.ndarray]:
    """Boolean masks ``{colour: (rows, cols)}`` of each colour's photosites for an array window of ``shape``
    whose first pixel is pixel ``origin = (row, col)`` of the full array (the pattern's cell starts at the
    full array's (0, 0), so a window at an odd offset starts mid-cell).

    Examples
    --------
    >>> cfa_masks((2, 2), "RGGB")["red"].astype(int).tolist()
    [[1, 0], [0, 0]]
    >>> cfa_masks((2, 2), "RGGB", origin=(1, 1))["red"].astype(int).tolist()
    [[0, 0], [0, 1]]
    """
    check_choice("cfa pattern", pattern, CFA_PATTERNS)
    rows, cols = (int(n) for n in shape)
    r = (np.arange(rows) + int(origin[0])) % 2
    c = (np.arange(cols) + int(origin[1])) % 2
    out = {}
    for colour in CFA_COLOURS:
        m = np.zeros((rows, cols), dtype=bool)
        for sr, sc in cfa_sites(pattern, colour):
            m |= (r[:, None] == sr) & (c[None, :] == sc)
        out[colour] = m
    return out


def _plane(planes: Any, colour: str, index: int) -> np.ndarray:
    if callable(planes):
        return as_float_array(f"planes({colour!r})", planes(colour), ndim=2)
    if isinstance(planes, Mapping):
        if colour not in planes:
            raise InputError(f"planes: no {colour!r} plane; give red, green and blue")
        return as_float_array(f"planes[{colour!r}]", planes[colour], ndim=2)
    return planes[..., index]


def mosaic(
    planes: np.ndarray | Mapping[str, Any] | Callable[[str], Any],
    pattern: str,
    *,
    origin: tuple[int, int] = (0, 0),
) -> np.ndarray:
    """The raw mosaic: each photosite keeps its own colour's value.

    Parameters
    ----------
    planes : ndarray (rows, cols, 3), mapping or callable
        The scene formed in each colour's band (red, green, blue): an RGB array, a mapping ``{colour: 2-D
        array}`` or a callable ``colour -> 2-D array`` (all of one shape).
    pattern : {"RGGB", "GRBG", "GBRG", "BGGR"}
    origin : (row, col)
        The window's first pixel in the full array (:func:`cfa_masks`).

    Returns
    -------
    ndarray (rows, cols), float

    Examples
    --------
    >>> rgb = np.stack([np.full((2, 2), 1.0), np.full((2, 2), 2.0), np.full((2, 2), 3.0)], axis=-1)
    >>> mosaic(rgb, "RGGB").tolist()
    [[1.0, 2.0], [2.0, 3.0]]
    """
    check_choice("cfa pattern", pattern, CFA_PATTERNS)
    if not callable(planes) and not isinstance(planes, Mapping):
        planes = as_float_array("planes", planes, ndim=3)
        if planes.shape[-1] != 3:
            raise InputError(f"planes has shape {planes.shape}: an RGB image must be (rows, cols, 3)")
    raw: np.ndarray | None = None
    masks: dict[str, np.ndarray] = {}
    for i, colour in enumerate(CFA_COLOURS):
        p = _plane(planes, colour, i)
        if raw is None:
            raw = np.zeros(p.shape, dtype=float)
            masks = cfa_masks(p.shape, pattern, origin=origin)
        elif p.shape != raw.shape:
            raise InputError(f"planes: the {colour} plane has shape {p.shape}, the red one {raw.shape}")
        raw[masks[colour]] = p[masks[colour]]
    assert raw is not None  # three colours
    return raw


def demosaic(raw, pattern: str, *, method: str = "bilinear") -> np.ndarray:
    """Interpolate a raw Bayer mosaic into an RGB image with colour-demosaicing.

    ``method``: ``"bilinear"`` (each missing colour the mean of its nearest same-colour neighbours),
    ``"malvar2004"`` (Malvar, He & Cutler, "High-quality linear interpolation for demosaicing of
    Bayer-patterned color images", ICASSP 2004: bilinear corrected by the Laplacian of the known colour) or
    ``"menon2007"`` (Menon, Andriani & Calvagno, "Demosaicing with directional filtering and a posteriori
    decision", IEEE Trans. Image Process. 16(1), 2007, with its refining step). Each keeps the measured value at
    its own photosite; a uniform grey mosaic stays exactly grey, borders included (the mosaic is extended by
    mirror reflection about its edge photosites first, which keeps the pattern's phase).

    Returns
    -------
    ndarray (rows, cols, 3), float: red, green, blue

    Examples
    --------
    >>> rgb = demosaic(np.full((6, 6), 0.5), "RGGB", method="malvar2004")
    >>> rgb.shape, float(np.ptp(rgb))
    ((6, 6, 3), 0.0)
    """
    check_choice("cfa pattern", pattern, CFA_PATTERNS)
    check_choice("method", method, DEMOSAIC_METHODS)
    data = as_float_array("raw", raw, ndim=2)
    if min(data.shape) < 2:
        raise InputError(f"raw has shape {data.shape}: a Bayer mosaic needs at least 2 x 2 photosites")
    printing = np.get_printoptions()  # colour-science sets numpy's legacy (1.13) printing when imported
    try:
        with warnings.catch_warnings():  # its modules import scipy.ndimage.filters (deprecated in SciPy 1.8)
            warnings.simplefilter("ignore", DeprecationWarning)
            import colour_demosaicing  # lazy: its import (colour-science) takes about a second
    finally:
        np.set_printoptions(**printing)  # the caller's, not a side effect of demosaicing

    # extend the mosaic by whole-sample mirror reflection about its edge photosites (an even width, so the
    # pattern's phase and each site's colour are kept): colour-demosaicing's convolutions reflect about the
    # edge itself, which puts other colours' values beside the border
    pad = _PAD_PX
    ext = np.pad(data, pad, mode="reflect")
    rgb = getattr(colour_demosaicing, DEMOSAIC_METHODS[method])(ext, pattern)
    return np.asarray(rgb, dtype=float)[pad:-pad, pad:-pad]


def luminance(rgb) -> np.ndarray:
    """The luma of a linear RGB image, ``0.2126 R + 0.7152 G + 0.0722 B`` (ITU-R BT.709-6): the grey level of
    a neutral scene, the image a demosaiced edge's luminance MTF is measured on.

    Examples
    --------
    >>> round(float(luminance(np.full((1, 1, 3), 0.4))[0, 0]), 12)
    0.4
    """
    data = as_float_array("rgb", rgb, ndim=3)
    if data.shape[-1] != 3:
        raise InputError(f"rgb has shape {data.shape}: must be (rows, cols, 3)")
    return data @ np.asarray(REC709_LUMA)


@dataclass(frozen=True)
class FalseColour:
    """Result of :func:`false_colour_amplitude`: ``peak`` and ``rms`` of the chroma over the region, as
    fractions of ``step`` (the edge's luma step, or the mean luma where the region is uniform), and
    ``chroma`` itself per pixel (NaN outside the region)."""

    peak: float
    rms: float
    step: float
    chroma: np.ndarray


def false_colour_amplitude(
    rgb,
    *,
    roi: tuple[int, int, int, int] | None = None,
    valid=None,
    reference=(1.0, 1.0, 1.0),
    step: float | None = None,
) -> FalseColour:
    """The false colour of a demosaiced image across a neutral edge.

    Definition (satchain's): each channel is first divided by the scene's ``reference`` colour (neutral by
    default), so the true scene is grey; the chroma of a pixel is then the rms of its opponent differences,
    ``C = sqrt(((R - G)^2 + (B - G)^2) / 2)``, 0 on the grey axis. The amplitude is C relative to the edge
    step: ``peak = max C / step`` and ``rms = sqrt(mean C^2) / step`` over the region (``roi`` = (x0, y0, x1,
    y1), half-open, and/or the ``valid`` mask: e.g. the pixels within a few px of the edge), with ``step`` the
    luma (:func:`luminance`) rise across the edge, its 95th minus its 5th percentile over the region, unless
    given. A uniform region (step 0) is measured against its mean luma. A neutral edge whose colours are
    interpolated exactly shows 0; demosaicing shows colour fringes where the colour planes, sampled on
    different lattices, are interpolated differently: the "false colour" or "colour fringe" artefact of
    demosaicing (Gunturk et al., "Demosaicking: color filter array interpolation", IEEE Signal Process. Mag.
    22(1), 2005).

    Examples
    --------
    >>> grey = np.repeat(np.linspace(0.2, 0.8, 8)[None, :, None], 3, axis=2) * np.ones((4, 1, 1))
    >>> false_colour_amplitude(grey).peak
    0.0
    """
    data = as_float_array("rgb", rgb, ndim=3)
    if data.shape[-1] != 3:
        raise InputError(f"rgb has shape {data.shape}: must be (rows, cols, 3)")
    ref = as_float_array("reference", reference, ndim=1)
    if ref.shape != (3,) or np.any(ref <= 0):
        raise InputError(f"reference = {reference!r}: must be three positive values (red, green, blue)")
    region = np.ones(data.shape[:2], dtype=bool)
    if valid is not None:
        region &= np.asarray(valid, dtype=bool)
    if roi is not None:
        x0, y0, x1, y1 = (int(v) for v in roi)
        box = np.zeros_like(region)
        box[max(y0, 0) : y1, max(x0, 0) : x1] = True
        region &= box
    if not region.any():
        raise InputError(f"roi = {roi!r} and valid leave no pixel to measure")
    bal = data / ref
    r, g, b = bal[..., 0], bal[..., 1], bal[..., 2]
    chroma = np.sqrt(0.5 * ((r - g) ** 2 + (b - g) ** 2))
    y = luminance(bal)[region]
    if step is None:
        lo, hi = np.percentile(y, [5.0, 95.0])
        step = float(hi - lo) if hi - lo > 1e-9 * max(abs(hi), abs(lo), 1e-300) else float(abs(np.mean(y)))
    c = chroma[region]
    if not np.any(c > 0):
        return FalseColour(0.0, 0.0, float(step), np.where(region, chroma, np.nan))
    if not step > 0:
        raise InputError(f"step = {step!r}: the region has no luma to measure its chroma against")
    return FalseColour(
        float(np.max(c) / step), float(np.sqrt(np.mean(c**2)) / step), float(step), np.where(region, chroma, np.nan)
    )
