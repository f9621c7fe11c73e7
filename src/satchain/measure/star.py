"""Siemens-star MTF (sinusoidal star, ISO 12233:2017 s-SFR style).

A sinusoidal star of ``cycles`` periods per revolution has, at radius ``r`` px, the local spatial frequency
``f = cycles / (2 pi r)`` cy/px along the tangent.  Radii ``r`` are spaced by ``annulus_px``; the pixels whose
centres fall within ``1.5 annulus_px`` of ``r`` are fitted, by least squares at their exact polar angles (no
interpolation, which would add its own blur), with ``a + b cos(n th) + c sin(n th)`` whose amplitude may vary
quadratically with the radius (and, per direction, with the angle to the sector's axis); the modulation at
``r`` is ``sqrt(b^2 + c^2) / a`` and the MTF is modulation / input modulation.  (A constant amplitude per 1-px
annulus was biased by up to 0.02 near Nyquist for a star centred on or near a pixel centre; see ``_annuli``.)

Directions.  The fit is done separately in pairs of opposite 45-deg sectors, one pair per direction of the
*frequency* (the tangent): ``ACT`` (x; sectors above and below the centre), ``ALT`` (y; sectors left and
right), ``D45`` (the diagonal along which x and y increase together) and ``D135`` (the other diagonal).
Angles are measured in image axes (x = column to the right, y = row downwards).

Validation and estimation (issue 10).  The centre is estimated to sub-pixel from the data (or a given
approximate centre refined): the per-annulus fits' residual is minimised over the centre (see
:mod:`satchain.measure._starfit`), with its covariance.  That minimisation needs a start within ~1 px, so a
given centre is first searched, within 6 px, for the point about which the ``cycles``-th angular harmonic adds
up coherently (issue 18: a centre 3 px off was refused with a message about ``--cycles``); a centre farther
off is refused naming the centre.  The claimed ``cycles`` must be the dominant angular
harmonic of the outer radii and stand well above the other harmonics (the noise), otherwise the call is
refused naming the count found.  The input (zero-frequency) modulation is, unless given, extrapolated from
the outer radii by a weighted fit of ``log m(f) = c0 + c1 f + c2 f^2`` (exact for a Gaussian MTF, and
within a few 0.1 % for diffraction, whose MTF is linear at 0: no MTF shape is assumed beyond smoothness).
Every MTF value carries a 1-sigma from the per-annulus fit residuals and the input-modulation fit; the
amplitude is debiased for noise.  ``flags`` lists quality warnings (clipping, non-uniform illumination, low
contrast-to-noise, uncertain centre, far extrapolation); an MTF above 1.2 is refused, never reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._validate import check_positive, check_range
from satchain.errors import ConfigError, InputError
from satchain.measure._clipping import resolve_full_scale
from satchain.measure._common import ResultMixin, clipping_flag, crop_roi, masked_as_nan
from satchain.measure._starfit import (
    StarFrame,
    annulus_fit,
    coarse_center,
    fit_center,
    harmonic_spectrum,
    polar,
    star_map,
    symmetry_center,
)
from satchain.units import cy_per_px_to_cy_per_m_ground

__all__ = ["StarResult", "measure_star", "STAR_DIRECTIONS"]

#: Frequency direction (deg from +x, y downwards) of each reported MTF.
STAR_DIRECTIONS = {"ACT": 0.0, "D45": 45.0, "ALT": 90.0, "D135": 135.0}


@dataclass(frozen=True)
class StarResult(ResultMixin):
    """MTF per direction against frequency (ascending), from a sinusoidal Siemens star.

    ``mtf`` maps each of ``ACT, ALT, D45, D135`` to an array aligned with ``f_cy_per_px``; ``mtf_all`` uses
    every angle.  ``mtf_at_nyquist`` per direction is None where the star does not reach 0.5 cy/px.
    ``*_std`` are 1-sigma uncertainties (noise); ``center_xy_px`` is the centre used (estimated or refined
    unless ``center_from == "given"``), ``center_std_px`` its 1-sigma in x and y; ``flags`` quality warnings;
    ``star_map`` the image-pixel-step -> star-frame map used (unit determinant; None: the image's own axes, a
    circular star; see ``image_affine`` of :func:`measure_star`).
    """

    f_cy_per_px: np.ndarray
    radius_px: np.ndarray
    mtf: dict
    mtf_all: np.ndarray
    mtf_at_nyquist: dict
    input_modulation: float
    center_xy_px: tuple[float, float]
    cycles: int
    f_cy_per_m_ground: np.ndarray | None = None
    mtf_std: dict | None = None
    mtf_all_std: np.ndarray | None = None
    mtf_at_nyquist_std: dict | None = None
    input_modulation_std: float = 0.0
    input_modulation_from: str = "given"
    center_std_px: tuple[float, float] | None = None
    center_from: str = "given"
    noise_std: float = 0.0
    contrast_to_noise: float | None = None
    flags: tuple = ()
    star_map: tuple | None = None


#: Largest MTF value reported; anything above is refused (wrong input modulation or not a star).
MTF_MAX = 1.2


def _log_quadratic_m0(f, mod, sig, f_hi: float) -> tuple[float, float]:
    """``exp(c0)`` and its 1-sigma from the weighted fit ``log m = c0 + c1 f + c2 f^2`` over ``f <= f_hi``."""
    sel = f <= f_hi
    if np.count_nonzero(sel) < 6:
        sel = np.argsort(f)[: min(6, f.size)]
    fs, ms = f[sel], mod[sel]
    ss = np.where(np.isfinite(sig[sel]) & (sig[sel] > 0), sig[sel], 0.0) + 1e-12 * ms
    w = ms / ss  # 1 / sigma of log m
    deg = 2 if fs.size >= 5 else 1
    design = np.vander(fs, deg + 1, increasing=True) * w[:, None]
    beta, *_ = np.linalg.lstsq(design, np.log(ms) * w, rcond=None)
    chi2 = float(np.sum((np.log(ms) * w - design @ beta) ** 2) / max(fs.size - deg - 1, 1))
    cov = np.linalg.pinv(design.T @ design) * max(chi2, 1.0)
    m0 = float(np.exp(beta[0]))
    return m0, float(m0 * np.sqrt(cov[0, 0]))


def _extrapolated_modulation(f: np.ndarray, mod: np.ndarray, sig: np.ndarray | None = None) -> tuple[float, float]:
    """Modulation at zero frequency and its 1-sigma, from the outer radii (no MTF shape assumed beyond
    smoothness): the weighted fit of ``log m = c0 + c1 f + c2 f^2`` over ``f <= 2 f_min``.

    Gaussian blur is exactly quadratic in ``log m``; diffraction (linear at 0) is caught by ``c1``.  The
    1-sigma adds, to the fit's noise, the change of ``m0`` when the range grows to ``f <= 3 f_min``,
    beyond its noise, doubled (the model error of the extrapolation, large when the outer MTF is far below 1).
    """
    sig = np.full_like(mod, np.nan) if sig is None else sig
    ok = np.isfinite(mod) & (mod > 0)
    f, mod, sig = f[ok], mod[ok], sig[ok]
    if f.size < 3:
        return (float(np.median(mod)) if f.size else float("nan")), float("nan")
    m0, s0 = _log_quadratic_m0(f, mod, sig, 2.0 * f.min())
    hi, s_hi = _log_quadratic_m0(f, mod, sig, 3.0 * f.min())
    model = np.sqrt(max((hi - m0) ** 2 - abs(s0**2 - s_hi**2), 0.0))  # nested fits: noise part removed
    return m0, float(np.hypot(s0, 2.0 * model))


#: How far (px) a given centre may be from the star's: a coarse search of the centre covers it.
CENTER_SEARCH_PX = 6.0


def _locate(data, n, start, r_in, r_out, given: bool, refine: bool, sm=None):
    """Centre (x, y), its 1-sigma (sx, sy) or None, and how it was obtained.  Without a given centre the
    start is the centre of point symmetry; a given one is first searched within :data:`CENTER_SEARCH_PX` for
    the coherent ``n``-th harmonic (``coarse_center``); the claimed cycles are checked there, then refined."""
    lin = None if sm is None else sm[0]
    if not refine:
        _check_cycles(data, n, start[0], start[1], r_in, r_out, lin)
        return start, None, "given"
    given_xy = start
    if not given:
        start = symmetry_center(data)
        r_out = min(r_out, _inside_radius(data.shape, start, sm))
        _check_extent(n, r_in, r_out, 1.0, n / (2 * np.pi * r_in))
    search = CENTER_SEARCH_PX if given else 1.5
    r_lo = max(r_in, n / (2 * np.pi * 0.35))
    if r_out - r_lo < 6:
        r_lo = r_in
    cx, cy, at_limit = coarse_center(data, n, start, r_lo, r_out, search_px=search, lin=lin)
    try:
        _check_cycles(data, n, cx, cy, r_in, r_out, lin)
    except InputError:
        if given and at_limit:  # the harmonic peaks on the search border: the centre or the cycles?
            _far_centre(data, n, given_xy, r_in, sm)  # always raises
        raise
    x, y, cov = fit_center(data, n, (cx, cy), r_lo, r_out, search_px=1.0, lin=lin)
    if cov is None:
        raise InputError(f"image: the star centre cannot be determined (no star with {n} cycles near {start})")
    moved = float(np.hypot(x - given_xy[0], y - given_xy[1])) if given else float(np.hypot(x - cx, y - cy))
    if moved > (CENTER_SEARCH_PX * np.sqrt(2) + 1.0 if given else 3.0):
        raise InputError(
            f"center = ({given_xy[0]:g}, {given_xy[1]:g}): the fitted star centre ({x:.2f}, {y:.2f}) is "
            f"{moved:.1f} px from it; give a centre within {CENTER_SEARCH_PX:g} px"
        )
    return (x, y), (float(np.sqrt(cov[0, 0])), float(np.sqrt(cov[1, 1]))), "refined" if given else "estimated"


def _far_centre(data, n, given_xy, r_in, sm=None) -> None:
    """A given centre from which no ``n``-cycle star is found: refused about the centre when the region's
    centre of point symmetry holds an ``n``-cycle star (or none at all), about the cycles (naming the count
    found there) when another count dominates there."""
    sx, sy = symmetry_center(data)
    r_out = _inside_radius(data.shape, (sx, sy), sm)
    where = ""
    try:
        _check_cycles(data, n, sx, sy, r_in, r_out, None if sm is None else sm[0])
        where = f" (a {n}-cycle star is centred near ({sx:.1f}, {sy:.1f}))"
    except InputError as exc:
        if "dominant angular harmonic" in str(exc):  # another count dominates at the star's centre
            raise
    raise InputError(
        f"center = ({given_xy[0]:g}, {given_xy[1]:g}): no centre of a {n}-cycle star found within "
        f"{CENTER_SEARCH_PX:g} px of it{where}; give the centre within {CENTER_SEARCH_PX:g} px, or omit it to "
        "estimate it from the data"
    )


def _check_cycles(data, n, xc, yc, r_in, r_out, lin=None) -> None:
    """Refuse when ``n`` is not the dominant angular harmonic of the outer radii, or does not stand out."""
    r_lo = max(r_in, 0.6 * r_out)
    m_max = int(max(3 * n, n + 10))
    m_max = min(m_max, int(np.pi * r_lo)) if np.pi * r_lo > n + 2 else m_max
    m, amp, noise = harmonic_spectrum(data, xc, yc, r_lo, r_out, m_max, lin)
    top = int(m[np.argmax(amp)])
    if top != n:
        raise InputError(
            f"cycles = {n}: the dominant angular harmonic at radii {r_lo:.0f}-{r_out:.0f} px about "
            f"({xc:.1f}, {yc:.1f}) is {top} cycles per revolution, not {n} (wrong --cycles, no star there, or a "
            "centre far off)"
        )
    if not amp[n - 1] > 6 * noise:
        raise InputError(
            f"image: no star found: the {n}-cycle harmonic ({amp[n - 1]:.3g}) is not above the other "
            f"harmonics (median {noise:.3g}) at radii {r_lo:.0f}-{r_out:.0f} px"
        )


def _inside_radius(shape, centre, sm=None) -> float:
    """The largest star-frame radius whose image (a circle, or an ellipse through the map ``sm``) about
    ``centre`` lies inside a region of ``shape`` (pixel centres)."""
    (ny, nx), (xc, yc) = shape, centre
    (ex, ey), (mx, my) = ((1.0, 1.0), (0.0, 0.0)) if sm is None else sm[2:4]
    return min((xc - mx) / ex, (yc - my) / ey, (nx - 1 - xc - mx) / ex, (ny - 1 - yc - my) / ey)


def _geometry(data, n, center, radius_px, f_max, sm=None):
    """Start centre, outer and inner radius (checked)."""
    ny, nx = data.shape
    xc, yc = ((nx - 1) / 2, (ny - 1) / 2) if center is None else (float(center[0]), float(center[1]))
    if not (0 <= xc <= nx - 1 and 0 <= yc <= ny - 1):  # (a NaN is refused here too)
        raise InputError(
            f"center = ({xc:g}, {yc:g}): outside the region (x in [0, {nx - 1}], y in [0, {ny - 1}] px); give "
            "the star's approximate centre in pixels of the region"
        )
    r_out = _inside_radius(data.shape, (xc, yc), sm) if radius_px is None else float(radius_px)
    return xc, yc, r_out, max(n / (2 * np.pi * f_max), 2.0)


def _check_extent(n, r_in, r_out, annulus_px, f_max, centre=None) -> None:
    """Refuse an outer radius too small for the annuli; ``centre``: a given centre that set it (named instead)."""
    if not r_out > r_in + 3 * annulus_px:
        what = f"radius_px = {r_out:g}"
        if centre is not None:
            what = f"center = ({centre[0]:g}, {centre[1]:g}): {r_out:g} px from the region's edge"
        raise InputError(
            f"{what}: the star must extend beyond {r_in + 3 * annulus_px:g} px "
            f"(the radius where {n} cycles reach f_max = {f_max:g} cy/px)"
        )


def measure_star(
    image,
    *,
    cycles: int,
    center=None,
    radius_px: float | None = None,
    roi=None,
    input_modulation: float | None = None,
    annulus_px: float = 1.0,
    f_max_cy_per_px: float = 0.75,
    pixel_m: float | None = None,
    refine_center: bool = True,
    full_scale: float | None = None,
    image_affine=None,
    row_offsets_px=None,
) -> StarResult:
    """Measure the MTF per direction from a sinusoidal Siemens star.

    Parameters
    ----------
    image : array_like, 2-D
        The image; NaN (nodata) and a numpy masked array's masked pixels are refused inside ``roi``.
    cycles : int
        Periods per revolution of the star (>= 4); checked against the data.
    center : (x, y), optional
        Approximate star centre in pixels of the (cropped) image, within 6 px of the star's (searched for the
        coherent ``cycles``-th angular harmonic, then refined from the data, unless ``refine_center=False``);
        by default estimated from the data, starting at the region's centre of point symmetry.
    radius_px : float, optional
        Outer radius used; the largest circle inside the region by default.
    roi : (x0, y0, x1, y1), optional
    input_modulation : float, optional
        Modulation (max - min) / (max + min) of the star itself, in (0, 1] (``ConfigError`` otherwise).  When
        not given it is extrapolated to zero frequency from the outer radii by a weighted fit of
        ``log m = c0 + c1 f + c2 f^2`` (see the module docstring); a flag is raised when the outer MTF is below
        0.8 (far extrapolation).
    annulus_px : float
        Spacing of the radii reported (px); each is fitted on the pixels within ``1.5 annulus_px`` of it.
    f_max_cy_per_px : float
        Smallest radius used is ``cycles / (2 pi f_max)``.
    pixel_m : float, optional
        Ground sample distance; adds ``f_cy_per_m_ground``.
    refine_center : bool
        Estimate/refine the centre from the data (default).  With False, ``center`` (or the region's centre)
        is used as it is.
    full_scale : float, optional
        The sensor's full scale in the image's units; integer images default to their dtype maximum.  The
        star is flagged ``clipping`` only on evidence: pixels at the full scale, or a flat run at its top
        (bottom) that shows saturation (:func:`satchain.measure.find_clipping`).
    image_affine : affine.Affine or (a, b, c, d, e, f), optional
        The image's geometry, scene metres -> image ``(col, row)`` (as :func:`satchain.measure.auto.measure_auto`
        takes it; only its linear part is used): a pushbroom image sheared, scaled along track or turned (Earth
        rotation, a line-rate error, a yaw) images the star as an ellipse.  Radii and angles are then computed in
        the star's own frame (the ground, scaled to unit determinant: radii in the image's mean pixels, ``sqrt
        |det|`` per metre), so the spokes are fitted on the star's true phase; each direction's MTF is reported
        at the image's own frequency along it: the sector whose gratings have their image wave vector along the
        direction (``ACT`` = +x, ``ALT`` = +y, in image pixels), fitted at the star radius where that wave vector
        is ``f_cy_per_px`` cycles per image pixel (see :func:`satchain.measure._starfit.star_map`).  ``mtf_all``
        and ``radius_px`` are then in the star's frame (mean pixels).  Without it an elliptical star is measured
        as if circular: its phase drifts around each circle and the MTF is wrong (or the star is refused).
    row_offsets_px : (du, dv), optional
        Per row of ``image`` (before ``roi``), the image-pixel offsets that a line of sight moving in time gives
        whole rows (oscillations, jitter; :class:`satchain.prediction.image_geometry.ImageGeometry`): row
        ``i``, column ``j`` sees the star where the mean map (``image_affine``, or the plain grid) puts ``(j +
        du_i, i + dv_i)``.  Each pixel is placed there, so the rows are aligned and the MTF is the blur about each
        row's mean position (what the budget's motion terms give); without them a star over rows displaced
        differently is measured with the displacements folded in (lower, and not the budget's).

    Raises
    ------
    InputError
        No star with ``cycles`` periods (another harmonic dominates, or none stands above the noise), an
        undeterminable centre, a region too small, or an MTF above 1.2 (wrong ``input_modulation``).

    Examples
    --------
    >>> y, x = np.mgrid[0:121, 0:121] - 60.3
    >>> star = 100 + 50 * np.cos(16 * np.arctan2(y, x))
    >>> r = measure_star(star, cycles=16)
    >>> round(float(r.mtf["ACT"][0]), 3), round(r.input_modulation, 6), np.round(r.center_xy_px, 3).tolist()
    (1.0, 0.5, [60.3, 60.3])
    """
    n, f_max, input_modulation = _check_args(cycles, annulus_px, f_max_cy_per_px, input_modulation)
    full_scale = resolve_full_scale(image, full_scale)
    data = crop_roi(masked_as_nan("image", image), roi, min_size=16)  # masked pixels: nodata, refused in the region
    if data.max() == data.min():
        raise InputError(f"image: the region is flat (every pixel = {data.min():g}); no star to measure")
    sm = _star_frame(image_affine, row_offsets_px, np.shape(image)[0], roi)
    (xc, yc), r_in, r_out, c_std, c_from = _centre_and_radii(
        data, n, center, radius_px, annulus_px, f_max, refine_center, sm
    )
    radii, mods, sigs, levels, noise, gradient = _annuli(data, n, xc, yc, r_in, r_out, annulus_px, sm)
    f = n / (2 * np.pi * radii)
    m0, m0_std, m0_from = _input_modulation(f, mods, sigs, input_modulation)
    order = np.argsort(f)
    f = f[order]
    mtf, std = _normalised(mods, sigs, order, m0, m0_std)
    _check_range_of_mtf(mtf, f, m0, m0_from)
    nyq = {k: _at_nyquist(f, mtf[k]) for k in STAR_DIRECTIONS}
    nyq_std = {k: (_at_nyquist(f, std[k], mtf[k]) if nyq[k] is not None else None) for k in STAR_DIRECTIONS}
    amp_outer = float(np.nanmedian(mods["all"][order][:5] * levels[order][:5]))
    cnr = amp_outer / noise if noise > 0 else None
    flags = _flags(data, levels, c_std, cnr, float(mtf["all"][0]), input_modulation is None, noise, gradient)
    flags[:0] = [c for c in [clipping_flag(data, full_scale=full_scale, noise_std=noise)] if c]
    return StarResult(
        f_cy_per_px=f,
        radius_px=radii[order],
        mtf={k: mtf[k] for k in STAR_DIRECTIONS},
        mtf_all=mtf["all"],
        mtf_at_nyquist=nyq,
        input_modulation=m0,
        center_xy_px=(float(xc), float(yc)),
        cycles=n,
        f_cy_per_m_ground=None if pixel_m is None else cy_per_px_to_cy_per_m_ground(f, gsd_m=pixel_m),
        mtf_std={k: std[k] for k in STAR_DIRECTIONS},
        mtf_all_std=std["all"],
        mtf_at_nyquist_std=nyq_std,
        input_modulation_std=float(m0_std),
        input_modulation_from=m0_from,
        center_std_px=c_std,
        center_from=c_from,
        noise_std=float(noise),
        contrast_to_noise=cnr,
        flags=tuple(flags),
        star_map=None if sm is None else sm[4],
    )


def _star_frame(image_affine, row_offsets_px, n_rows: int, roi):
    """``(frame, directions, extent, margin, lin)`` for the helpers (see :func:`~satchain.measure._starfit.
    star_map`; ``frame`` is ``lin`` or a :class:`~satchain.measure._starfit.StarFrame` with the region's row
    offsets, ``margin`` their largest size in x and y), or None on the image's own plain grid."""
    if image_affine is None and row_offsets_px is None:
        return None
    lin, dirs, extent = star_map(image_affine, STAR_DIRECTIONS)
    if row_offsets_px is None:
        return lin, dirs, extent, (0.0, 0.0), lin
    try:
        du, dv = (np.asarray(v, dtype=float) for v in row_offsets_px)
    except (TypeError, ValueError):
        raise ConfigError("row_offsets_px: must be two sequences (du, dv) of image-pixel offsets") from None
    if du.shape != (n_rows,) or dv.shape != (n_rows,) or not (np.isfinite(du).all() and np.isfinite(dv).all()):
        raise ConfigError(
            f"row_offsets_px: shapes {du.shape} and {dv.shape}: must be {n_rows} finite offsets each (one per row)"
        )
    y0, y1 = (0, n_rows) if roi is None else (int(roi[1]), int(roi[3]))
    du, dv = du[max(y0, 0) : y1], dv[max(y0, 0) : y1]
    margin = (float(np.max(np.abs(du), initial=0.0)), float(np.max(np.abs(dv), initial=0.0)))
    return StarFrame(lin, du, dv), dirs, extent, margin, lin


def _at_nyquist(f, curve, valid=None) -> float | None:
    """``curve`` at 0.5 cy/px, linear between its finite points (of ``valid`` too); None outside them."""
    ok = np.isfinite(curve) & (np.isfinite(valid) if valid is not None else True)
    if np.count_nonzero(ok) < 2 or not f[ok][0] <= 0.5 <= f[ok][-1]:
        return None
    return float(np.interp(0.5, f[ok], curve[ok]))


def _check_args(cycles, annulus_px, f_max_cy_per_px, input_modulation):
    """The checked options of :func:`measure_star`: (cycles, f_max, input modulation or None)."""
    n = int(check_range("cycles", cycles, 4, 10000))
    check_positive("annulus_px", annulus_px)
    f_max = check_range("f_max_cy_per_px", f_max_cy_per_px, 0.0, 2.0, lo_open=True)
    if input_modulation is not None:  # (max - min) / (max + min) of a non-negative star: in (0, 1]
        if isinstance(input_modulation, bool):
            raise ConfigError(f"input_modulation = {input_modulation!r}: must be a number in (0, 1], not a bool")
        input_modulation = check_range("input_modulation", input_modulation, 0.0, 1.0, lo_open=True)
    return n, f_max, input_modulation


def _centre_and_radii(data, n, center, radius_px, annulus_px, f_max, refine_center, sm=None):
    """The centre used, the inner and outer radius (checked against the centre found), the centre's 1-sigma and
    how it was obtained."""
    xc, yc, r_out, r_in = _geometry(data, n, center, radius_px, f_max, sm)
    _check_extent(n, r_in, r_out, annulus_px, f_max, (xc, yc) if center is not None and radius_px is None else None)
    (xc, yc), c_std, c_from = _locate(data, n, (xc, yc), r_in, r_out, center is not None, refine_center, sm)
    r_fit = _inside_radius(data.shape, (xc, yc), sm)  # the largest star circle about the centre found
    r_out = r_fit if radius_px is None else min(r_out, r_fit)
    _check_extent(n, r_in, r_out, annulus_px, f_max)
    return (xc, yc), r_in, r_out, c_std, c_from


def _input_modulation(f, mods, sigs, given):
    """The star's own modulation, its 1-sigma and where it comes from (given, or extrapolated to zero
    frequency from the outer radii: refused where that is too uncertain)."""
    if given is None:
        m0, m0_std = _extrapolated_modulation(f, mods["all"], sigs["all"])
        m0_from = "extrapolated from the outer radii"
        if not m0_std <= 0.25 * m0:
            raise InputError(
                f"input_modulation: cannot be extrapolated from the outer radii ({m0:.3g} +- {m0_std:.2g}; the "
                "MTF there is far below 1): give the star's own modulation"
            )
    else:
        m0 = given
        m0_std, m0_from = 0.0, "given"
    if not m0 > 1e-4:
        raise InputError("image: no star modulation found at the outer radii (flat region or wrong cycles?)")
    return m0, m0_std, m0_from


def _normalised(mods, sigs, order, m0, m0_std):
    """MTF and its 1-sigma per direction (and ``all``), by ascending frequency: modulation / ``m0``."""
    rel = m0_std / m0 if np.isfinite(m0_std) else 0.0
    mtf, std = {}, {}
    for k in [*STAR_DIRECTIONS, "all"]:
        mtf[k] = mods[k][order] / m0
        std[k] = np.sqrt((sigs[k][order] / m0) ** 2 + (mtf[k] * rel) ** 2)
    return mtf, std


def _annuli(data, n, xc, yc, r_in, r_out, annulus_px, sm=None):
    """Per-annulus modulation and 1-sigma, all angles and per direction; mean level; pooled noise sigma;
    relative peak-to-peak illumination change across the outer circles.

    Each radius ``r`` is fitted on the pixels of the band ``r +- 1.5 annulus_px`` (inside ``r_out``) with an
    amplitude quadratic in the radius offset ``dr`` (its value at ``dr = 0`` is reported) and, per direction,
    also in the angle ``psi`` to the sector's axis (its mean over uniform ``psi`` is reported, as the sector's
    MTF is defined).  A constant amplitude over a 1-px annulus was biased by up to 0.02 near Nyquist for a
    star centred on or near a pixel centre: the local amplitude changes by a few % across the annulus (and
    across a sector under anisotropic blur), and the least-squares fit averages it with weights set by where
    the pixels fall on the wave, which the lattice makes non-uniform (see the README's star section).

    Through a star map ``sm`` (:func:`~satchain.measure._starfit.star_map`) radii and angles are the star
    frame's, and each direction is fitted on its own radii ``r s`` (:func:`_direction_fits`).
    """
    ny, nx = data.shape
    y, x = np.mgrid[0:ny, 0:nx]
    rr, th = polar(x.ravel(), y.ravel(), xc, yc, None if sm is None else sm[0])
    v = data.ravel()
    radii = np.arange(r_out - annulus_px / 2, r_in, -annulus_px)
    mods = {k: np.full(radii.size, np.nan) for k in [*STAR_DIRECTIONS, "all"]}
    sigs = {k: np.full(radii.size, np.nan) for k in mods}
    levels = np.empty(radii.size)
    res, grads = [], []
    half = 1.5 * annulus_px
    for i, r in enumerate(radii):
        sel = (rr >= r - half) & (rr < min(r + half, r_out))
        t, val, dr = th[sel], v[sel], (rr[sel] - r) / annulus_px
        a, amp, sb, s, g = annulus_fit(t, val, n, (dr, dr * dr))
        if a <= 0:
            raise InputError("image: the star's mean level must be positive to define a modulation")
        levels[i], mods["all"][i], sigs["all"][i] = a, amp / a, sb / a
        res.append(s)
        grads.append(g)
        for k, (mk, sk) in (_sector_fits(t, val, dr, n) if sm is None else {}).items():
            mods[k][i], sigs[k][i] = mk, sk
    if sm is not None:
        _direction_fits(rr, th, v, n, radii, (r_in, r_out), annulus_px, sm[1], mods, sigs)
    third = max(3, radii.size // 3)  # outer radii: residual = noise, little model error
    gradient = 2 * float(np.median(grads[:third]))  # peak-to-peak relative level change across a circle
    return radii, mods, sigs, levels, float(np.median(res[:third])), gradient


#: Half-width (rad) of each direction's pair of opposite sectors.
SECTOR_HALF = np.pi / 8


def _direction_fits(rr, th, v, n, radii, limits, annulus_px, dirs, mods, sigs) -> None:
    """Through a star map: direction ``k``'s tangent is at star-frame angle ``beta`` and star radius ``rho`` gives
    its image frequency ``s n / (2 pi rho)`` cy/px, so the value reported at radius ``r`` (frequency ``n / (2 pi
    r)``) is fitted at ``rho = r s`` (NaN where that falls outside ``limits = (r_in, r_out)``); fills
    ``mods`` and ``sigs`` in place."""
    r_in, r_out = limits
    half = 1.5 * annulus_px
    for k, (beta, scale) in dirs.items():
        for i, rho in enumerate(radii * scale):
            if not r_in < rho <= r_out - annulus_px / 2 + 1e-9:
                continue
            sel = (rr >= rho - half) & (rr < min(rho + half, r_out))
            got = _sector_fits(th[sel], v[sel], (rr[sel] - rho) / annulus_px, n, {k: beta})
            if k in got:
                mods[k][i], sigs[k][i] = got[k]


def _sector_fits(t, val, dr, n, axes=None) -> dict:
    """Modulation and its 1-sigma per direction (pairs of opposite sectors), from one band of pixels; ``axes``:
    direction -> the polar angle (rad) of its tangent (default: :data:`STAR_DIRECTIONS`)."""
    out = {}
    axes = {k: np.deg2rad(a) for k, a in STAR_DIRECTIONS.items()} if axes is None else axes
    for k, beta in axes.items():
        psi = np.angle(np.exp(2j * (t - beta - np.pi / 2))) / 2  # angle to the sector axis, both sides
        m = np.abs(psi) <= SECTOR_HALF
        if np.count_nonzero(m) >= 24:  # 11 coefficients
            q = psi[m] ** 2 - SECTOR_HALF**2 / 3  # zero mean over uniform psi
            ak, ampk, sbk, *_ = annulus_fit(t[m], val[m], n, (dr[m], dr[m] ** 2, q))
            if ak > 0:
                out[k] = (ampk / ak, sbk / ak)
    return out


def _check_range_of_mtf(mtf: dict, f: np.ndarray, m0: float, m0_from: str) -> None:
    worst = max(float(np.nanmax(m)) for m in mtf.values())
    if worst > MTF_MAX:
        k = int(np.nanargmax(mtf["all"]))
        raise InputError(
            f"input_modulation = {m0:.4g} ({m0_from}): the MTF would reach {worst:.3g} > {MTF_MAX} "
            f"(all-angle {mtf['all'][k]:.3g} at {f[k]:.3f} cy/px); the input modulation is too small"
        )


def _flags(data, levels, c_std, cnr, mtf_outer: float, extrapolated: bool, noise: float, gradient: float) -> list[str]:
    """Quality warnings (strings) for the JSON and the tables."""
    flags = []
    spread = (levels.max() - levels.min()) / np.mean(levels)
    if spread > 0.05:
        flags.append(f"non-uniform illumination: the mean level varies by {100 * spread:.0f} % across radii")
    if gradient > 0.05:
        flags.append(f"non-uniform illumination: the mean level varies by {100 * gradient:.0f} % across the star")
    if c_std is not None and max(c_std) > 0.1:
        flags.append(f"uncertain centre: 1-sigma ({c_std[0]:.2f}, {c_std[1]:.2f}) px > 0.1 px")
    if cnr is not None and cnr < 10:
        flags.append(f"low contrast-to-noise: star amplitude / noise = {cnr:.1f} < 10")
    if extrapolated and mtf_outer < 0.8:
        flags.append(
            f"input modulation extrapolated from an outer MTF of {mtf_outer:.2f} < 0.8: "
            "give the star's own modulation for an accurate curve"
        )
    return flags
