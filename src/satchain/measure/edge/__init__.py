"""Slanted-edge MTF (ISO 12233:2017 e-SFR, with accuracy improvements).

Conventions
-----------
* The MTF is measured **along the edge normal**, in cycles per pixel along that normal.  An edge nearly
  parallel to the image y axis (columns vary across it) measures the ACT (x) MTF; an edge nearly parallel to
  x measures the ALT (y) MTF.  ``direction`` says which.
* ``angle_deg`` is the angle of the edge line from the image y axis (ALT), in (-90, 90]: positive when the
  edge moves to larger x as y increases.  Near-vertical edges have small angles, near-horizontal ones angles
  near +-90.
* The ESF is normalised to 0 on the dark side and 1 on the bright side, with ``esf_x_px`` the signed distance
  from the edge along the normal (dark side negative).

Algorithm (ISO 12233:2017 annex D, plus the improvements marked *)
-----------------------------------------------------------------
1. Per-row (per-column for ALT) centroid of the [-1/2, 0, 1/2] derivative inside a window that follows the
   edge, then a *robust (Tukey bisquare) polynomial fit over the whole ridge*, iterated; *the degree (1-3) is
   chosen from the data* (a higher degree only when it explains the positions far beyond their noise and moves
   the edge by more than 0.1 px), so gently curved edges are followed.
2. Projection of every pixel onto the local edge normal; averaging in bins of ``1/oversampling`` px, *or, where
   the rows' sub-pixel phases gather in n clusters (tilts near atan(1/n), short edges), on the natural lattice
   of spacing cos(t) / n* (no empty bins, no interpolation).  *Each bin is corrected for the positions of its
   samples* (first and second moments; ISO leaves a 2.5 % loss at Nyquist).
3. *The region is validated*: one edge (straight plateaus on both sides, per-line steps alike, edge positions
   that line up), no clipped plateau; *a linear illumination gradient along the normal is removed*.
   First difference of the binned ESF, corrected for its transfer function ``sinc(f w)``.
4. *Noise-adaptive regularisation*: the LSF is kept raw inside a Tukey window of half-width ``W`` around the
   edge; the part outside it is Gaussian-smoothed (``win g + S((1 - win) g)``).  Only the tails are smoothed,
   so no mass of the core moves (smoothing the whole ESF read a Gaussian-like PSF 0.02 low at 0.1-0.15 cy/px
   once the window shrank to 5 px at SNR <= 100), the smoothed tails keep the low-frequency mass of long
   (e.g. diffraction) tails, so the normalisation at f = 0 is not biased by the window, and they add almost
   no high-frequency noise.  ``W`` is the largest half-width whose predicted noise on the MTF at
   Nyquist (propagated exactly from the per-bin noise) stays below ``noise_target``.
5. MTF(f) = |DFT(LSF)(f)| / DFT(LSF)(0) / corrections, evaluated directly at the output frequencies, with
   its *standard deviation at every frequency propagated exactly (first order) from the measured noise*,
   taken per ESF level (shot noise: the bright side's noise, the dark side's and linear in between).
   An MTF leaving [0, 1.2] up to Nyquist is refused; quality flags (``flags``: codes, ``warnings``: text)
   report near-critical angles, curvature, illumination gradient, low contrast-to-noise and clipping, an
   *edge curvature the fit leaves that moves the MTF by > 0.01* (``curvature_bias``, e.g. a forced straight
   fit on a curved edge) and *quantised values too coarse for the step and not dithered by noise*
   (``quantisation``).

Edge metrics follow the GIQE (Leachtenauer et al. 1997, GIQE-4) definitions on the normalised ESF:
``rer = ESF(+0.5) - ESF(-0.5)`` and the overshoot ``H`` = the maximum of the ESF between 1.0 and 3.0 px on the
bright side if it peaks there, else (monotonic edge) ``ESF(1.25)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._deprecate import warn_renamed
from satchain._validate import check_positive, check_range
from satchain.errors import InputError
from satchain.measure._clipping import resolve_full_scale
from satchain.measure._common import (
    ResultMixin,
    robust_sigma,
    unmask,
)
from satchain.measure.edge._align import los_curves, on_grid
from satchain.measure.edge._axis import check_axis, line_coef, on_axis, oversampled_f_max
from satchain.measure.edge._checks import (
    CRITICAL_TILTS_DEG,
    check_model,
    check_saturation,
    check_single_edge,
    critical_angle_flags,
    curvature_bias_flag,
    curvature_shift,
    fit_plateaus,
    quantisation_flags,
    quantisation_step,
    unfitted_curvature,
)
from satchain.measure.edge._crossings import edge_line_fields, line_numbers
from satchain.measure.edge._locate import edge_region, locate_edge, orient_edge, project
from satchain.measure.edge._numerics import adaptive_mtf, bin_esf, choose_bins, rise_width
from satchain.measure.edge._numerics import flatten_rows as _flatten_rows
from satchain.measure.edge._numerics import trim_ends as _trim_ends
from satchain.measure.edge._result import NU_STEP as _NU_STEP
from satchain.measure.edge._result import result_fields

__all__ = ["EdgeResult", "measure_edge", "DEGENERATE_ANGLES_DEG"]

#: Edge tilts (from the nearest axis) where the per-row phases repeat after 1, 4, 3, 2 or 1 rows.
DEGENERATE_ANGLES_DEG = tuple(sorted(CRITICAL_TILTS_DEG))
_MTF_MAX = 1.2  # an MTF above this up to Nyquist is not a measurement
_LOW_CNR = 25.0  # contrast-to-noise below which the result is flagged
_LEVEL_MIN_SAMPLES = 50  # samples each side of the step's middle for the level-dependent noise (else pooled)
_CURVE_MTF_SHIFT = 0.01  # an edge curvature left by the fit moving the MTF (up to Nyquist) by more: flagged
_CURVE_SCREEN = 0.3  # ... computed exactly where the estimate from the positions' spread exceeds this x it


@dataclass(frozen=True)
class EdgeResult(ResultMixin):
    """Result of :func:`measure_edge`; frequencies are along the edge normal (``frequency_axis``).

    ``mtf_at_nyquist_sigma`` is the predicted 1-sigma noise of ``mtf_at_nyquist``
    (propagated from the measured pixel noise at each ESF level), ``mtf_sigma`` the same at every frequency;
    ``noise_sigma`` is that pixel noise pooled over both sides in image units; ``contrast`` the edge step,
    positive when the image rises along +x (ACT edges) or +y (ALT edges); ``cnr`` = |contrast| / noise_sigma
    (inf without noise).
    ``mtf50_cy_per_px`` is None (JSON null) when the MTF stays above 0.5 in the output band.
    ``flags`` are short machine-readable codes, ``warnings`` the matching sentences (same order).
    ``fit_degree`` is the degree of the edge-position polynomial used, ``curvature_per_px`` the edge curvature
    at the centre of the region (1 / radius, 0 for a straight fit), ``bin_width_px`` the ESF sample spacing,
    ``illumination_gradient_per_px`` the relative change of the step per px along the normal (removed).
    ``edge_point_xy`` is a point (x = column, y = row, px, in the image, ``roi`` offset included) on the fitted
    edge at its middle line: with ``angle_deg`` it places the edge line (to join collinear halves).
    ``frequency_axis`` is the axis of every frequency (``"normal"`` or ``"row"``, see :func:`measure_edge`)
    and ``frequency_scale`` = f_row / f_normal (``cos t``; 1 on the normal axis).
    ``lines`` are the image lines crossing the edge (rows for an ACT edge, columns for an ALT one; image
    coordinates, ``roi`` offset included) and ``edge_position_px`` where each crosses it (x for ACT, y for ALT;
    raw, not detrended; NaN / null where a line is not measured: its window leaves the region or touches an
    excluded or clipped pixel), with its 1-sigma ``edge_position_sigma_px``
    (:mod:`satchain.measure.edge._crossings`): line-of-sight motion from a long straight edge
    (:func:`satchain.measure.jitter.measure_jitter`).
    ``mtf_aligned`` is the MTF with each line located (:mod:`satchain.measure.edge._align`): the same curve as
    ``mtf`` unless ``fit_degree`` is forced; where the lines' positions wobble beyond their noise (flag
    ``line_of_sight_motion``) ``mtf``, ``mtf_at_nyquist``, the ESF, LSF, RER and overshoot are measured so, the
    budget's per-row motion terms' counterpart.  ``mtf_as_imaged`` (``mtf_as_imaged_sigma``,
    ``mtf_as_imaged_at_nyquist``) is the edge as imaged, ISO 12233's straight fit with the lines'
    displacements folded into the ESF (the same curve as ``mtf`` for a straight edge without motion; NaN
    beyond its own band), and ``los_motion_rms_px`` the rms departure of the located lines from that straight
    line (px).
    """

    f_cy_per_px: np.ndarray
    mtf: np.ndarray
    esf_x_px: np.ndarray
    esf: np.ndarray
    lsf: np.ndarray
    angle_deg: float
    direction: str
    mtf_at_nyquist: float
    mtf50_cy_per_px: float | None
    rer: float
    overshoot: float
    contrast: float
    noise_sigma: float
    window_half_width_px: float
    n_lines: int
    warnings: tuple[str, ...]
    f_cy_per_m_ground: np.ndarray | None = None
    f_cy_per_mm: np.ndarray | None = None
    mtf_sigma: np.ndarray | None = None
    mtf_at_nyquist_sigma: float = float("nan")
    flags: tuple[str, ...] = ()
    fit_degree: int = 1
    curvature_per_px: float = 0.0
    cnr: float = float("nan")
    bin_width_px: float = 0.25
    illumination_gradient_per_px: float = 0.0
    edge_point_xy: tuple[float, float] | None = None
    frequency_axis: str = "normal"
    frequency_scale: float = 1.0
    lines: np.ndarray | None = None
    edge_position_px: np.ndarray | None = None
    edge_position_sigma_px: np.ndarray | None = None
    mtf_aligned: np.ndarray | None = None
    mtf_as_imaged: np.ndarray | None = None
    mtf_as_imaged_sigma: np.ndarray | None = None
    mtf_as_imaged_at_nyquist: float = float("nan")
    los_motion_rms_px: float = float("nan")

    @property
    def edge_angle_deg(self) -> float:
        """Deprecated in satchain 0.1, removed in 0.2: ``angle_deg``."""
        warn_renamed("EdgeResult", "edge_angle_deg", "angle_deg")
        return self.angle_deg

    @property
    def mtf_at_nyquist_std(self) -> float:
        """Deprecated in satchain 0.1, removed in 0.2: ``mtf_at_nyquist_sigma``."""
        warn_renamed("EdgeResult", "mtf_at_nyquist_std", "mtf_at_nyquist_sigma")
        return self.mtf_at_nyquist_sigma


def measure_edge(
    image,
    *,
    roi=None,
    pixel_m: float | None = None,
    pitch_m: float | None = None,
    oversampling: int = 4,
    f_max_cy_per_px: float = 1.0,
    noise_target: float = 0.004,
    fit_degree: int | str = "auto",
    full_scale: float | None = None,
    saturation_level: float | None = None,
    debias: bool = False,
    valid=None,
    nodata: float | None = None,
    frequency_axis: str = "normal",
    edge_line=None,
) -> EdgeResult:
    """Measure the MTF (with its noise), ESF, LSF, RER and overshoot from a slanted edge.

    Parameters
    ----------
    image : array_like, 2-D
        Image containing one straight or gently curved edge (any real dtype, its values as they stand; a
        numpy masked array's masked pixels are excluded as ``valid = False`` ones are).
    roi : (x0, y0, x1, y1), optional
        Half-open pixel region to analyse; the whole image by default.
    pixel_m : float, optional
        Ground sample distance (m); adds ``f_cy_per_m_ground``.
    pitch_m : float, optional
        Detector pitch (m); adds focal-plane ``f_cy_per_mm``.
    oversampling : int
        ESF bins per pixel along the normal (ISO uses 4); >= 4.
    f_max_cy_per_px : float
        Highest output frequency (cy/px along the normal), in [0.5, oversampling / 4].  Where the edge phases
        only support a coarser ESF lattice (tilts near 45 deg) the output stops at that lattice's Nyquist
        frequency (flag ``band_limited``).
    noise_target : float
        Predicted noise on the MTF at Nyquist that the adaptive window aims at.
    fit_degree : int or "auto"
        Degree of the robust polynomial fitted to the edge positions: 1 (straight), 2 or 3 (curved, ISO
        12233:2017 allows them for lens distortion), or "auto" (default): chosen from the data.  A curvature
        the degree used leaves in the edge positions is flagged (``curvature_bias``) when it moves the MTF by
        more than 0.01.
    full_scale : float, optional
        The sensor's full scale in the image's units (e.g. ``2**bits - 1`` DN): pixels at it are clipped
        (refused above 1 % of the region, flagged ``clipping`` below); for integer images the dtype maximum
        by default.  Without it clipping is still named on evidence (a flat run at an extreme that shows
        saturation, see :func:`satchain.measure.find_clipping`); an edge's own plateau never is.
    saturation_level : float, optional
        The former name of ``full_scale`` (the same meaning; give one of them): deprecated in 0.1 (a
        ``SatchainDeprecationWarning``), removed in 0.2.
    debias : bool
        Subtract the predicted noise power from the squared MTF (removes the upward bias of noisy low MTF).
    valid : array_like of bool, optional
        Pixels to measure (the image's shape; True = measure), e.g. an area-of-interest mask.  Excluded
        pixels are left out of the edge location, the ESF bins and the noise estimate, and are never
        clipping; a line whose edge window touches one is not used.  Without ``valid`` and ``nodata`` the
        zeros of an integer image are excluded where they are evidently a fill (flag ``nodata_fill``; flag
        ``nodata_fill_unsure`` where they may be one but stay data: :mod:`satchain.measure._zero_fill`).
    nodata : float, optional
        Pixels equal to this value are excluded as well (NaN: NaN pixels).
    frequency_axis : {"normal", "row"}
        The frequency axis of the MTF.  ``"normal"`` (default, ISO 12233): along the edge normal.  ``"row"``:
        along the image row (ACT) or column (ALT), MTF_Estimator's (FidMTF's) convention, which projects the
        pixels on the row: for an edge tilted by ``t`` from the nearest pixel axis ``MTF_row(f) =
        MTF_normal(f / cos t)``, i.e. the normal axis scaled by ``cos t`` (``frequency_scale``; 0.957 at the
        Baotou target's 16.8 deg: the row MTF at Nyquist is the normal MTF at 0.522 cy/px).  Every frequency
        of the result (``f_cy_per_px``, ground, focal plane, MTF at Nyquist, MTF50) is then on the row axis;
        the ESF, LSF, RER and overshoot stay along the normal.  See :mod:`satchain.measure.edge._axis`.
    edge_line : (x, y, angle_deg), optional
        A known edge line (a point in the image, x = column, y = row, ``roi`` offset included, and the angle
        as ``angle_deg``), e.g. the joint line of two collinear halves of one target edge: the ESF is projected
        on it instead of the line fitted in the region (which still chooses the lines used).

    Returns
    -------
    EdgeResult

    Raises
    ------
    InputError
        No edge, more than one edge (a stripe, a corner), a flat, saturated or clipped region, NaN/inf, a
        region smaller than 12 px, an edge shorter than 8 lines, or an MTF outside [0, 1.2] up to Nyquist.

    Examples
    --------
    >>> y, x = np.mgrid[0:64, 0:64]
    >>> d = (x - 31.6) * np.cos(0.1) - (y - 31.5) * np.sin(0.1)
    >>> img = 0.1 + 0.8 / (1 + np.exp(-d / 0.6))  # a logistic edge tilted by 5.7 deg
    >>> r = measure_edge(img)
    >>> r.direction, round(r.angle_deg, 2), r.flags
    ('ACT', 5.73, ())
    """
    image, valid = unmask(image, valid)
    os_, f_max, deg, full_scale = _check_args(
        image, oversampling, f_max_cy_per_px, noise_target, fit_degree, full_scale, saturation_level
    )
    axis = check_axis(frequency_axis)
    data, ok, flags = edge_region(image, roi, valid, nodata)
    flags += check_saturation(data, full_scale, ok)
    work, okw, direction, transposed, sign = orient_edge(data, ok)
    line = None if edge_line is None else line_coef(edge_line, roi, transposed)
    q_step = quantisation_step(data if ok is None else data[ok])
    (coef, own), rows, slope, w, mode, (x, esf_raw, counts, sigma, sig_bins), esf_flags, ridge = _binned_esf(
        work, deg, os_, q_step, okw, line
    )
    flags += esf_flags
    esf_n, contrast, grad, g_flags, model = _normalise(x, esf_raw, counts, sigma, len(rows))
    flags += g_flags
    f_top = oversampled_f_max(f_max, axis, os_ / 4.0)
    f, mtf, mtf_sig, half_w = _mtf(x, esf_n, counts, sig_bins / contrast, (f_top, w, noise_target, debias), flags)
    flags += _curvature_flags(work, (rows, own, ridge), (os_, sigma, half_w), f, mtf, forced=deg is not None, valid=okw)
    flags += critical_angle_flags(slope, len(rows), mode, w)
    flags += _cnr_flags(contrast, sigma)
    f, mtf, mtf_sig, scale = on_axis(f, mtf, mtf_sig, slope, axis, f_max)
    lines = _line_positions(work, own, okw, (full_scale, sign), (transposed, roi), flags)

    def moved(shift):  # the curve of the ESF projected on the located edge moved line by line
        located = ((own, rows, [], ridge), shift)
        return _moved_curve(work, okw, located, (os_, sigma, contrast), (f_top, noise_target, debias), (axis, f_max))

    aligned, imaged, los, shift = los_curves(lines, (transposed, roi), own, moved if line is None else None, flags)
    shift = shift if deg is None else None  # the model's check along the edge as located (each line's own)
    check_model(work, project(work, np.arange(work.shape[0]), coef, shift)[0], x, esf_n, model, sigma, okw)
    if aligned is not None and deg is None:  # (a forced degree keeps its own fit as the headline)
        x, esf_n, (f, mtf, mtf_sig), half_w = aligned
    mtf_al = mtf if aligned is None else on_grid(f, aligned[2])[0]
    imaged = (mtf, mtf_sig) if imaged is None else on_grid(f, imaged)
    return EdgeResult(**result_fields(
        (f, mtf, mtf_sig, axis, scale), (x, esf_n), (coef, rows, slope, transposed, roi),
        (contrast * sign, sigma, half_w, w, grad, direction, flags), (pixel_m, pitch_m), lines,
        (mtf_al, *imaged, los),
    ))  # fmt: skip


def _moved_curve(work, valid, moved, stats, opts, axis_opts):
    """``(x, esf, (f, mtf, 1-sigma), window half-width)`` of the ESF on the located edge moved line by line
    (``moved = (locate_edge's result, per-line offsets)``; ``stats = (oversampling, noise, contrast)``, ``opts
    = (f_max, noise target, debias)``, ``axis_opts = (axis, f_max)``); None where it cannot be measured."""
    os_, sigma, contrast = stats
    f_top, noise_target, debias = opts
    try:
        _, rows, slope, w, _, (x, esf_raw, counts, _, sig_bins), _, _ = _binned_esf(
            work, None, os_, None, valid, None, moved
        )
        esf_n = _normalise(x, esf_raw, counts, sigma, len(rows))[0]
        f, mtf, sig, half_w = _mtf(x, esf_n, counts, sig_bins / contrast, (f_top, w, noise_target, debias), [])
    except InputError:
        return None
    return x, esf_n, on_axis(f, mtf, sig, slope, *axis_opts)[:3], half_w


def _line_positions(work, coef, valid, clip, where, flags):
    """(lines, edge position, 1-sigma) per line crossing the edge (:mod:`satchain.measure.edge._crossings`); all
    NaN (flag ``lines_unmeasured``) where the lines' profile cannot be estimated."""
    transposed, roi = where
    try:
        return edge_line_fields(work, coef, valid, clip, transposed, roi)
    except InputError as exc:
        flags.append(("lines_unmeasured", f"per-line edge positions not measured: {exc}"))
        nan = np.full(work.shape[0], np.nan)
        return line_numbers(work.shape[0], transposed, roi), nan, nan


def _check_args(image, oversampling, f_max_cy_per_px, noise_target, fit_degree, full_scale, saturation_level):
    """The checked options of :func:`measure_edge`: (oversampling, f_max, fit degree or None, full scale)."""
    os_ = int(check_range("oversampling", oversampling, 4, 32))
    f_max = check_range("f_max_cy_per_px", f_max_cy_per_px, 0.5, os_ / 4.0)
    check_positive("noise_target", noise_target)
    deg = _check_degree(fit_degree)
    if saturation_level is not None:
        warn_renamed("measure_edge", "saturation_level", "full_scale")
    return os_, f_max, deg, resolve_full_scale(image, full_scale, saturation_level)


def _cnr_flags(contrast: float, sigma: float) -> list:
    """``low_cnr`` below a contrast-to-noise of :data:`_LOW_CNR`."""
    if sigma > 0 and contrast / sigma < _LOW_CNR:
        return [("low_cnr", f"low contrast-to-noise {contrast / sigma:.1f} (< {_LOW_CNR:g}): MTF noise is large")]
    return []


def _mtf(x, esf_n, counts, rel_sigma, opts, flags):
    """The MTF, its 1-sigma and the window half-width on the output band (cut where the ESF lattice or the
    checked range stops it, flagged ``band_limited``); ``opts = (f_max, bin width, noise target, debias)``."""
    f_max, w, noise_target, debias = opts
    f = np.arange(0.0, min(f_max, 0.5 / w) + _NU_STEP / 2, _NU_STEP)
    if f[-1] < f_max - _NU_STEP / 2:
        flags.append(
            ("band_limited", f"the edge phases sample the ESF every {w:.3f} px: MTF given to {f[-1]:.2f} cy/px")
        )
    mtf, mtf_sig, half_w, _, _ = adaptive_mtf(x, esf_n, counts, rel_sigma, f, noise_target)
    if debias:
        mtf = np.sqrt(np.maximum(mtf**2 - mtf_sig**2, 0.0))
        mtf[0] = 1.0
    f, mtf, mtf_sig = _check_mtf(f, mtf, mtf_sig, flags)
    return f, mtf, mtf_sig, half_w


def _binned_esf(
    work: np.ndarray, deg: int | None, os_: int, q_step: float | None = None, valid=None, line=None, moved=None
):
    """Locate the edge, project and bin: ((coef used, coef fitted), rows, slope, bin width, bin mode, (x, esf,
    counts, sigma), flags, (lines, edge positions) of the ridge).  Pixels outside ``valid`` are left out.  With
    ``line`` (a degree-1 polynomial) the ESF is projected on that line, not on the one fitted.  ``moved =
    (locate_edge's result, per-line offsets)`` projects on the located polynomial moved line by line
    (:mod:`satchain.measure.edge._align`) without locating it again."""
    located, shift = (None, None) if moved is None else moved
    own, rows, flags, ridge = locate_edge(work, deg, valid) if located is None else located
    flags = list(flags)
    coef = own if line is None else line
    d, v, slope, phase = project(_lines(work, rows), rows, coef, None if shift is None else shift[rows])
    ok = None if valid is None else valid[rows].ravel()
    w, origin, mode = choose_bins(phase, 1.0 / np.hypot(1.0, slope), os_)
    if w > 0.75:
        raise InputError(
            f"image: the edge is within {np.degrees(np.arctan(abs(slope))):.2f} deg of the pixel axes and "
            f"{len(rows)} lines leave a {w:.2f} px gap in the sub-pixel phases; tilt the edge by 2-10 deg"
        )
    sel = slice(None) if ok is None else ok  # every sample (no valid mask): no masked copies
    x, esf_raw, counts = bin_esf(d[sel], v[sel], w, origin)
    v, r_flags, at = _flatten_rows(d, v, len(rows), x, esf_raw, ok)
    if r_flags:
        flags += r_flags
        x, esf_raw, counts = bin_esf(d[sel], v[sel], w, origin)
        at = np.interp(d, x, esf_raw)
    resid = (v - at)[sel]
    level_noise = _level_noise(at[sel], resid, esf_raw, counts)  # (before robust_sigma may overwrite them)
    sigma = robust_sigma(resid, overwrite=q_step is None)  # (the residuals are not needed after, then)
    if q_step is not None:
        flags += quantisation_flags(q_step, x, esf_raw, resid)
    x, esf_raw, counts = _trim_ends(x, esf_raw, counts)
    return (coef, own), rows, slope, w, mode, (x, esf_raw, counts, sigma, level_noise(esf_raw)), flags, ridge


def _level_noise(level: np.ndarray, resid: np.ndarray, esf: np.ndarray, counts: np.ndarray):
    """The pixel noise as a function of the ESF level: ``esf -> per-bin 1-sigma``.

    Shot noise makes the bright side noisier than the dark (variance linear in the signal, read noise its
    floor), and the MTF's noise comes from the bins of both sides: one pooled (median) estimate reads a
    value between the two and under-predicts the MTF's noise (1.4-1.6x at Nyquist on a simulated shot-noise
    edge).  The residuals of the samples below and above the middle of the step give the variance at each
    half's mean level; between them (and clamped beyond) the variance is interpolated linearly in the level.
    The residuals about the bins' means lose one degree of freedom per bin (``n / (n - bins)``: 1.2-1.5x in
    variance on a 24 px region at 1/8 px bins, where the MTF's noise was otherwise read 10-20 % low).
    """
    n, p = resid.size, int(np.count_nonzero(counts))
    dof = n / (n - p) if n > 2 * p else 2.0  # the residuals about the bins' means lose one sample per bin
    mid = 0.5 * (float(np.min(esf)) + float(np.max(esf)))
    lo = level < mid
    n_lo = int(np.count_nonzero(lo))
    if min(n_lo, lo.size - n_lo) < _LEVEL_MIN_SAMPLES:
        s = robust_sigma(resid) * np.sqrt(dof)
        return lambda e: np.full(np.shape(e), s)
    hi = ~lo
    pts = np.array([float(np.mean(level[lo])), float(np.mean(level[hi]))])
    var = np.array([robust_sigma(resid[lo]), robust_sigma(resid[hi])]) ** 2 * dof
    return lambda e: np.sqrt(np.interp(e, pts, var))


def _lines(work: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``work[rows]``, without a copy when ``rows`` are all the lines in order (the usual case)."""
    n = work.shape[0]
    if rows.size == n and (n == 0 or (rows[0] == 0 and rows[-1] == n - 1)):
        return work
    return work[rows]


def _curvature_flags(work, fit, opts, f, mtf, *, forced: bool, valid=None):
    """Flag ``curvature_bias`` when an edge curvature the fit leaves moves the MTF by more than 0.01.

    ``fit = (rows, coef, (lines, edge positions))``, ``opts = (oversampling, noise sigma, window half-width)``.
    :func:`unfitted_curvature` finds a departure of the positions from the fit resolved above their noise,
    with a first estimate from its spread; where that is not negligible the ESF is measured along the
    higher-degree edge and :func:`curvature_shift` gives the exact shift for this region.
    """
    rows, coef, (lines, pos) = fit
    os_, sigma, half_w = opts
    found = unfitted_curvature(lines, pos, coef, f, mtf)
    if found is None or found[0] <= _CURVE_SCREEN * _CURVE_MTF_SHIFT:
        return []
    _, _, spread, k = found
    try:
        (coef_k, _), _, _, _, _, (x, esf, counts, _, _), _, _ = _binned_esf(work, k, os_, None, valid)
        esf = _normalise(x, esf, counts, sigma, rows.size)[0]
    except InputError:  # the better edge is refused: keep the estimate from the spread
        shift, f_at = found[0], found[1]
    else:
        rr = rows.astype(float)
        slope = np.polyval(np.polyder(coef), rr) if len(coef) > 1 else np.zeros(rr.size)
        # a sample's true distance is its projected one minus the edge's departure along the normal
        r = -(np.polyval(coef_k, rr) - np.polyval(coef, rr)) / np.sqrt(1.0 + slope**2)
        d = project(_lines(work, rows), rows, coef)[0]
        r = np.repeat(r, work.shape[1])
        if valid is not None:
            d, r = d[valid[rows].ravel()], r[valid[rows].ravel()]
        shift, f_at = curvature_shift(d, r, x, esf, half_w, f)
    if shift <= _CURVE_MTF_SHIFT:
        return []
    return [curvature_bias_flag(len(coef) - 1, shift, f_at, spread, k, forced=forced)]


def _check_degree(fit_degree) -> int | None:
    """``"auto"`` -> None; else an int in 1..3."""
    if isinstance(fit_degree, str):
        if fit_degree.strip().lower() == "auto":
            return None
        try:
            fit_degree = int(fit_degree)
        except ValueError:
            raise InputError(f"fit_degree = {fit_degree!r}: must be 'auto', 1, 2 or 3") from None
    if isinstance(fit_degree, bool) or fit_degree not in (1, 2, 3):
        raise InputError(f"fit_degree = {fit_degree!r}: must be 'auto', 1, 2 or 3")
    return int(fit_degree)


def _normalise(x, esf, counts, sigma, n_lines):
    """Validate one edge, remove a linear illumination gradient along the normal and normalise to 0..1.

    Model: ``esf = a + b x + (c + e x) E(x)`` from straight-line fits of the two plateaus (beyond
    max(4 px, 2 rise distances)); returns (E, c, e / c, flags, (a, b, c, e)).
    """
    lim = max(4.0, 2.0 * rise_width(x, esf))
    (a, b), (a_hi, b_hi) = fit_plateaus(x, esf, lim)
    c, e = a_hi - a, b_hi - b
    if not c > 5 * sigma / np.sqrt(max(n_lines, 1)) or c <= 0:
        raise InputError("image: no edge found (step between the two sides is not above the noise)")
    check_single_edge(x, esf, counts, sigma, ((a, b), (a_hi, b_hi)), lim)
    span = float(x[-1] - x[0])
    flags = []
    # the gradient is removed only where it is resolved (its effect over the ESF above ~3 x its noise)
    sig_slope = sigma / np.sqrt(max(counts.sum(), 1) / 2.0) * np.sqrt(12.0) / max(span / 2, 1.0)
    if abs(b) * span < 3 * sig_slope * span and abs(e) * span < 3 * sig_slope * span:
        b, e = 0.0, 0.0
    denom = c + e * x
    if np.any(denom <= 0.1 * c):
        raise InputError("image: the edge step changes sign across the region; give an ROI around one edge")
    if max(abs(b), abs(e)) * span > 0.02 * c:
        flags.append(
            (
                "illumination_gradient",
                f"non-uniform illumination: the plateaus slope by {100 * max(abs(b), abs(e)) * span / c:.1f} % of "
                "the step across the region (removed as a linear gradient along the normal)",
            )
        )
    return (esf - a - b * x) / denom, float(c), float(e / c), flags, (a, b, c, e)


def _check_mtf(f, mtf, sig, flags):
    """Refuse an MTF outside [0, 1.2] up to Nyquist; cut the output band where it leaves it beyond."""
    bad = ~np.isfinite(mtf) | (mtf > _MTF_MAX)
    up_to_nyq = f <= 0.5 + 1e-9
    if np.any(bad & up_to_nyq):
        k = int(np.argmax(bad))
        raise InputError(
            f"image: the measured MTF reaches {mtf[k]:.3g} at {f[k]:.3f} cy/px (outside [0, {_MTF_MAX:g}]); "
            "the region does not hold one clean edge"
        )
    if np.any(bad):
        k = int(np.argmax(bad))
        flags.append(("band_limited", f"MTF above {_MTF_MAX:g} beyond {f[k]:.2f} cy/px (noise): output stops there"))
        return f[:k], mtf[:k], sig[:k]
    return f, mtf, sig
