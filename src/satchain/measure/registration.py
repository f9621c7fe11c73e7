"""Band-to-band registration: the subpixel offset between two images of the same ground, with its 1-sigma.

**Sign convention.** ``offset_px = (dy_alt, dx_act)`` is where ``image``'s content lies relative to
``reference``'s: a feature at ``(y, x)`` in ``reference`` is at ``(y + dy, x + dx)`` in ``image``, so that
``image(y, x) = reference(y - dy, x - dx)``. A band whose content sits 0.3 px further across track (larger
column) than the reference's has ``dx_act = +0.3``. Shifting ``image`` by ``-offset_px``
(``scipy.ndimage.shift(image, -offset)``) maps it onto ``reference``; this is the opposite sign of
scikit-image's ``phase_cross_correlation`` ``shift`` (the shift that registers the moving image).

**Method** (two estimators in series, no scikit-image needed):

1. *Phase correlation* (Kuglin & Hines 1975) of the two regions, each less its mean and under a Hann window:
   the integer peak of the inverse FFT of the normalised cross-power spectrum, then refined to ``1 / upsample``
   px by the matrix-multiply DFT of Guizar-Sicairos, Thurman & Fienup, "Efficient subpixel image registration
   algorithms", Opt. Lett. 33, 156 (2008) (scikit-image's ``phase_cross_correlation``), evaluated on a
   1.5 px neighbourhood only. A peak of either sign is taken: a band whose contrast is inverted (vegetation,
   red against NIR) registers as well as one that is not.
2. *Least squares* (Lucas & Kanade 1981; Gauss-Newton): the offset, a gain and a bias minimising
   ``sum (R(x - d/2) - a I(x + d/2) - b)^2`` over the usable pixels, both images first band-limited by one
   Gaussian (``smooth_px``, 1 px by default). The warp is symmetric (each image moves by half the offset, by
   quintic-spline interpolation, the splines' coefficients computed once). The band limit is what makes the
   estimate accurate: a spline's interpolation error grows steeply towards Nyquist, and content near Nyquist
   (sharp edges, aliased texture) biases an unfiltered fit by up to 0.04 px; filtered, the bias is below
   0.002 px on textures up to 0.48 cy/px, edges and bars (tests/measure/test_registration.py). The gain absorbs the
   bands' different radiometry (negative: inverted contrast). The phase correlation's estimate is the start;
   iterations stop when the step is below 1e-5 px.

**1-sigma** (``sigma_noise_px``): Cramer-Rao-like, from the images themselves. The estimate's error is
``-(J^T J)^-1 J^T H n``: ``J`` the derivatives of the residual with respect to (dy, dx, gain, bias) -- the
images' gradient content (a 5-point central difference of the warped images) --, ``n`` the white noise of both
images, ``H`` the band limit. Its covariance ``sigma_w^2 (J^T J)^-1 (H J)^T (H J) (J^T J)^-1`` (for an
unfiltered fit, ``sigma_dx^2 = sigma_w^2 / sum(g_x^2)``) takes ``sigma_w^2`` (the noise of reference + gain^2 x
image per pixel) from the residual at the optimum, per degree of freedom, over the variance the band limit and
the warp leave of white noise. The residual holds both images' noise and whatever else the model leaves
(content that differs between the bands), so the sigma is that of the data, not of a noise model; noise that is
not white (correlated between pixels) makes it approximate. Checked by Monte Carlo (tests: the spread of the
estimates over noise realisations is within 30 % of the reported sigma on textures, edges and bars).
``sigma_px`` adds :data:`FLOOR_PX` (0.001 px, the interpolation's measured accuracy floor) in quadrature, so
that a low-noise image's sigma never claims more than the method delivers.

**Pixel grids.** ``scale`` = pitch of ``image`` / pitch of ``reference`` (an integer: 4 for a multispectral band
against its panchromatic reference): ``reference`` is block-averaged over each of ``image``'s pixel footprints
(``scale x scale`` of its pixels; the grids' corners are taken to coincide at the top-left) and the offset is
measured, and given, in ``image``'s pixels. A reference coarser than the image: swap the two and negate the
offset. ``roi`` is in the measuring (coarser) grid's pixels; ``mask`` is one array on one grid, else a pair
``(reference_mask, image_mask)``, each on its own image's grid. Content above the coarser grid's Nyquist
frequency aliases there and does not move with the offset: it biases the estimate (a camera's optics keep it
small; the tests render content up to the MS band's Nyquist).

**Refused** (:class:`~satchain.errors.InputError`, one line, never a plausible wrong number): shapes that differ
(beyond ``scale``), NaN/inf outside the mask, a flat or featureless region (no correlation between the images,
no gradient, or gradients in one direction only: an offset along a single straight edge is undetermined), an
offset beyond ``max_offset`` of the region's side, a sigma above ``max_sigma_px``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from scipy import ndimage as ndi

from satchain._validate import as_float_array, check_range, split_mask
from satchain.errors import InputError, ResourceLimitError
from satchain.measure._common import ResultMixin, crop_roi, fill_invalid

__all__ = [
    "FLOOR_PX",
    "MAX_PIXELS",
    "METHOD",
    "MIN_ISOTROPY",
    "SMOOTH_PX",
    "RegistrationResult",
    "block_mean",
    "measure_registration",
]

#: What ``method`` says.
METHOD = (
    "phase correlation (Hann window, upsampled DFT: Guizar-Sicairos 2008) + symmetric Gauss-Newton least squares "
    "(Gaussian band limit, quintic-spline warp, gain and bias)"
)
_SPLINE_ORDER: Final = 5
_SPLINE_MODE: Final = "mirror"
#: the band limit's default: the sigma (px) of the Gaussian both images pass before the least squares
SMOOTH_PX = 1.0
#: the accuracy floor (1-sigma, px) added in quadrature to the noise's sigma: what the interpolation leaves of a
#: noise-free offset after the band limit (<= 0.0011 px over shifts of -2..2 px on textures with content up to
#: 0.48 cy/px; < 0.0005 px on edges and bars: tests/measure/test_registration.py)
FLOOR_PX = 0.001
#: pixels beyond half the offset kept clear of the border and of masked pixels (the spline's reach)
_GUARD_PX = 4
_MAX_ITER = 40
_STEP_TOL_PX = 1e-5
#: the largest region registered at once (its working arrays take ~240 bytes per pixel: 4 GiB)
MAX_PIXELS = 16_000_000
#: least eigenvalue ratio of the 2 x 2 gradient matrix: below it the gradients run in one direction only
MIN_ISOTROPY = 1e-3
_DERIVATIVE = np.array([1.0, -8.0, 0.0, 8.0, -1.0]) / 12.0  # 5-point central difference (correlate1d)


@dataclass(frozen=True)
class RegistrationResult(ResultMixin):
    """The offset of ``image`` from ``reference`` (see the module's sign convention).

    ``offset_px``: (dy_alt, dx_act), ``image``'s content relative to ``reference``'s, in the measuring grid's
    pixels (``image``'s); ``sigma_px``: their 1-sigma (the noise's and the accuracy floor :data:`FLOOR_PX`);
    ``sigma_noise_px``: the noise's alone; ``covariance_px2``: the noise's ((var_y, cov), (cov, var_x));
    ``method``; ``correlation``: Pearson correlation of the two aligned, band-limited regions (negative:
    inverted contrast); ``phase_peak``: the phase-correlation peak (1: identical content, ~0: none); ``gain``,
    ``bias``: reference ~ gain x image + bias; ``noise_rms``: the white noise per pixel of reference +
    gain^2 x image that the residual implies; ``n_pixels`` / ``usable_fraction``: the pixels the least squares
    used (the region less its border, the masked pixels and their neighbourhood); ``scale``: the pitch ratio;
    ``phase_offset_px``: the phase correlation's own estimate; ``iterations``; ``flags``: ``inverted_contrast``,
    ``low_correlation`` (|correlation| < 0.5), ``masked`` (the mask excluded pixels)."""

    offset_px: tuple[float, float]
    sigma_px: tuple[float, float]
    sigma_noise_px: tuple[float, float]
    covariance_px2: tuple[tuple[float, float], tuple[float, float]]
    method: str
    correlation: float
    phase_peak: float
    gain: float
    bias: float
    noise_rms: float
    n_pixels: int
    usable_fraction: float
    scale: int
    phase_offset_px: tuple[float, float]
    iterations: int
    flags: tuple[str, ...] = ()


# ----------------------------------------------------------------------------------------------- preparation


def block_mean(a: np.ndarray, scale: int, valid: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """``a`` averaged over ``scale x scale`` blocks from the top-left corner (rows and columns past the last
    whole block dropped), and the blocks' validity (every pixel of the block valid; None: all valid).

    Examples
    --------
    >>> block_mean(np.arange(16.0).reshape(4, 4), 2)[0].tolist()
    [[2.5, 4.5], [10.5, 12.5]]
    """
    ny, nx = (n // scale for n in a.shape)
    a = np.asarray(a, dtype=np.float64)[: ny * scale, : nx * scale]
    out = a.reshape(ny, scale, nx, scale).mean(axis=(1, 3))
    if valid is None:
        return out, None
    v = np.asarray(valid, dtype=bool)[: ny * scale, : nx * scale]
    return out, np.asarray(v.reshape(ny, scale, nx, scale).all(axis=(1, 3)))


def _split_masks(mask, ref_shape, img_shape, scale):
    if mask is None:
        return None, None
    if isinstance(mask, tuple | list):
        if len(mask) != 2:
            raise InputError(f"mask: a pair (reference_mask, image_mask) has 2 items, got {len(mask)}")
        pair = mask
    elif scale == 1:
        pair = (mask, mask)
    else:
        raise InputError("mask: with scale > 1 give a pair (reference_mask, image_mask), each of its image's shape")
    out = []
    for name, m, shape in (("reference", pair[0], ref_shape), ("image", pair[1], img_shape)):
        if m is None:
            out.append(None)
            continue
        m = np.asarray(m)
        if m.dtype != bool or m.shape != shape:
            raise InputError(f"mask ({name}): must be a boolean array of the {name}'s shape {shape}, got "
                             f"{m.dtype} of shape {m.shape}")  # fmt: skip
        out.append(m)
    return out[0], out[1]


def _as_image(name: str, value) -> tuple[np.ndarray, np.ndarray | None]:
    data, masked = split_mask(name, value)
    a = as_float_array(name, data, ndim=2, finite=False)
    return a, (None if masked is None else ~masked)


def _check_finite(name: str, a: np.ndarray, valid: np.ndarray | None) -> None:
    bad = ~np.isfinite(a) if valid is None else ~np.isfinite(a) & valid
    if bad.any():
        raise InputError(f"{name}: {int(np.count_nonzero(bad))} NaN/inf value(s) outside the mask; give mask= "
                         "(True = usable) to leave nodata out")  # fmt: skip


def _and(a: np.ndarray | None, b: np.ndarray | None) -> np.ndarray | None:
    return b if a is None else a if b is None else a & b


def _check_size(shape, roi) -> None:
    """Refuse up front a region whose working arrays (~30 float64 copies) would exceed :data:`MAX_PIXELS`."""
    if roi is not None and not hasattr(roi, "to_roi") and len(tuple(roi)) == 4:
        x0, y0, x1, y1 = (int(v) for v in roi)
        shape = (max(y1 - y0, 0), max(x1 - x0, 0))
    n = int(np.prod(shape))
    if n > MAX_PIXELS:
        raise ResourceLimitError(f"image: a region of {shape[0]} x {shape[1]} px would need ~{n * 240 / 2**30:.1f} "
                                 f"GiB; registration takes at most {MAX_PIXELS:.3g} px: give a roi")  # fmt: skip


def _prepare(reference, image, roi, mask, scale):
    """Both images on the measuring grid, cropped to ``roi``: (R, I, valid or None)."""
    r, r_ok = _as_image("reference", reference)
    i, i_ok = _as_image("image", image)
    _check_size(i.shape, roi)
    m_r, m_i = _split_masks(mask, r.shape, i.shape, scale)
    r_ok, i_ok = _and(r_ok, m_r), _and(i_ok, m_i)
    _check_finite("reference", r, r_ok)
    _check_finite("image", i, i_ok)
    if scale == 1 and r.shape != i.shape:
        raise InputError(f"reference and image: shapes {r.shape} and {i.shape} differ; give scale (the pitch "
                         "ratio) for images of different pixel sizes, or crop them to one grid")  # fmt: skip
    if scale > 1:
        if tuple(n // scale for n in r.shape) != i.shape:
            raise InputError(f"reference of shape {r.shape} at scale = {scale}: its {scale} x {scale} blocks "
                             f"make {tuple(n // scale for n in r.shape)}, not the image's shape {i.shape}")  # fmt: skip
        r = fill_invalid(np.where(np.isfinite(r), r, 0.0), r_ok)
        r, r_ok = block_mean(r, scale, r_ok)
    valid = _and(r_ok, i_ok)
    if valid is not None and not valid.any():
        raise InputError("mask: every pixel is excluded; nothing to register")
    r = fill_invalid(np.where(np.isfinite(r), r, 0.0), valid)
    i = fill_invalid(np.where(np.isfinite(i), i, 0.0), valid)
    if roi is not None:
        r, i = crop_roi(r, roi, name="reference", min_size=16), crop_roi(i, roi, name="image", min_size=16)
        if valid is not None:
            x0, y0, x1, y1 = (int(v) for v in (roi.to_roi() if hasattr(roi, "to_roi") else roi))
            valid = valid[y0:y1, x0:x1]
    elif min(r.shape) < 16:
        raise InputError(f"image: region of shape {r.shape} is too small; both sides must be >= 16 px")
    if valid is not None and valid.all():
        valid = None
    return r, i, valid


# ----------------------------------------------------------------------------------------- phase correlation


def _hann(n: int) -> np.ndarray:
    return 0.5 - 0.5 * np.cos(2 * np.pi * (np.arange(n) + 0.5) / n)


def _phase_correlation(r: np.ndarray, i: np.ndarray, valid, upsample: int) -> tuple[float, float, float]:
    """(dy, dx, peak) of the phase correlation: ``i``'s content relative to ``r``'s; the peak's signed height."""
    ny, nx = r.shape
    w = np.outer(_hann(ny), _hann(nx)) * (1.0 if valid is None else valid)
    wsum = float(w.sum())
    fr = np.fft.fft2((r - float((r * w).sum()) / wsum) * w)
    fi = np.fft.fft2((i - float((i * w).sum()) / wsum) * w)
    cross = np.conj(fr) * fi  # c(s) = sum_x r(x) i(x + s): its peak is at the content's offset s = d
    mag = np.abs(cross)
    spectrum = cross / (mag + 1e-12 * float(mag.max() or 1.0))
    c = np.fft.ifft2(spectrum).real
    k = int(np.argmax(np.abs(c)))
    py, px = divmod(k, nx)
    d = np.array([py - ny if py > ny // 2 else py, px - nx if px > nx // 2 else px], dtype=float)
    # Guizar-Sicairos: the DFT of the spectrum on a (1.5 px)^2 neighbourhood of the peak at 1 / upsample px
    m = int(math.ceil(1.5 * upsample))
    steps = (np.arange(m) - m // 2) / upsample
    ky = np.exp(2j * np.pi * np.outer(d[0] + steps, np.fft.fftfreq(ny)))
    kx = np.exp(2j * np.pi * np.outer(d[1] + steps, np.fft.fftfreq(nx)))
    fine = (ky @ spectrum @ kx.T).real / (ny * nx)
    j = int(np.argmax(np.abs(fine)))
    jy, jx = divmod(j, m)
    return float(d[0] + steps[jy]), float(d[1] + steps[jx]), float(fine[jy, jx])


# ----------------------------------------------------------------------------------------------- least squares


def _warp(coeffs: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """The spline (coefficients ``coeffs``) sampled at x - shift: out(x) = image(x - shift)."""
    return ndi.shift(coeffs, shift, order=_SPLINE_ORDER, mode=_SPLINE_MODE, prefilter=False)


def _gradient(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return (ndi.correlate1d(a, _DERIVATIVE, axis=0, mode="mirror"),
            ndi.correlate1d(a, _DERIVATIVE, axis=1, mode="mirror"))  # fmt: skip


def _usable(shape, valid, d0: np.ndarray, smooth_px: float) -> np.ndarray:
    """Pixels whose band-limited, warped values reach neither the border nor a masked pixel (half the offset,
    3 sigma of the band limit and a guard for the spline)."""
    reach = int(math.ceil(float(np.max(np.abs(d0))) / 2 + 0.5 + 3 * smooth_px)) + _GUARD_PX
    ok = np.zeros(shape, dtype=bool)
    ok[reach:-reach, reach:-reach] = True
    if valid is not None:
        ok &= ~ndi.maximum_filter(~valid, size=2 * reach + 1, mode="constant", cval=False)
    return ok


def _residual(cr, ci, d, a, b, use):
    rw, iw = _warp(cr, d / 2), _warp(ci, -d / 2)
    return rw, iw, (rw - a * iw - b)[use]


def _jacobian(rw, iw, a, use) -> np.ndarray:
    gry, grx = _gradient(rw)
    giy, gix = _gradient(iw)
    # r = R(x - d/2) - a I(x + d/2) - b:  dr/dd = -(grad R_w + a grad I_w) / 2, dr/da = -I_w, dr/db = -1
    cols = [-(gry + a * giy)[use] / 2, -(grx + a * gix)[use] / 2, -iw[use], -np.ones(int(use.sum()))]
    return np.stack(cols, axis=1)


def _gauss_newton(r, i, use, d0, min_correlation):
    """Offset, gain, bias (and the warped images, residual, Jacobian, iterations) minimising the residual."""
    cr = ndi.spline_filter(r, order=_SPLINE_ORDER, mode=_SPLINE_MODE)
    ci = ndi.spline_filter(i, order=_SPLINE_ORDER, mode=_SPLINE_MODE)
    d = np.array(d0, dtype=float)
    rw, iw, _ = _residual(cr, ci, d, 1.0, 0.0, use)
    _check_correlation(float(np.corrcoef(rw[use], iw[use])[0, 1]), min_correlation)
    a, b = np.polyfit(iw[use], rw[use], 1)
    step, n = np.inf, 0
    while n < _MAX_ITER:
        rw, iw, res = _residual(cr, ci, d, a, b, use)
        jac = _jacobian(rw, iw, a, use)
        if n == 0:
            _check_isotropy(jac)
        delta = np.linalg.lstsq(jac, -res, rcond=None)[0]
        d, a, b = d + delta[:2], a + delta[2], b + delta[3]
        n += 1
        step = float(np.max(np.abs(delta[:2])))
        if step < _STEP_TOL_PX:
            break
    if step > 1e-3:
        raise InputError(f"image: the least-squares offset did not converge (last step {step:.2g} px after {n} "
                         "iterations): the region's content does not fix the offset")  # fmt: skip
    rw, iw, res = _residual(cr, ci, d, a, b, use)
    return d, float(a), float(b), rw, iw, res, _jacobian(rw, iw, a, use), n


def _noise_factor(shift: np.ndarray, smooth_px: float) -> float:
    """The variance a unit white noise keeps through the band limit (Gaussian of ``smooth_px``) and the spline
    warp by ``shift``: the sum of the squared weights of their combined kernel (separable: one factor per axis)."""
    out = 1.0
    for s in shift:
        h = np.zeros(129)
        h[64] = 1.0
        if smooth_px > 0:
            h = ndi.gaussian_filter1d(h, smooth_px, mode="constant")
        out *= float(np.sum(ndi.shift(h, float(s), order=_SPLINE_ORDER, mode=_SPLINE_MODE) ** 2))
    return out


def _covariance(jac, res, use, d, smooth_px) -> tuple[np.ndarray, float]:
    """(2 x 2 covariance of the offset, the white-noise variance per pixel of reference + gain^2 x image).

    The estimate's error is ``-(J^T J)^-1 J^T H n`` (``n``: the two images' white noise; ``H``: the band limit
    and the warp), of covariance ``sigma_w^2 (J^T J)^-1 (H J)^T (H J) (J^T J)^-1`` (``H J``: each column of
    ``J`` as an image, zero off the usable pixels, through the Gaussian; the warp passes the band-limited columns
    whole); ``sigma_w^2``: the residual variance per degree of freedom over :func:`_noise_factor`."""
    dof = max(res.size - jac.shape[1], 1)
    s2 = float(res @ res) / dof / _noise_factor(d / 2, smooth_px)
    info = jac.T @ jac
    if smooth_px > 0:
        cols = []
        for k in range(jac.shape[1]):
            col = np.zeros(use.shape)
            col[use] = jac[:, k]
            cols.append(ndi.gaussian_filter(col, smooth_px, mode="constant").ravel())
        hj = np.stack(cols, axis=1)
        meat = hj.T @ hj
    else:
        meat = info
    try:
        inv = np.linalg.inv(info)
    except np.linalg.LinAlgError:
        return np.full((2, 2), np.inf), s2
    return (inv @ meat @ inv)[:2, :2] * s2, s2


# ------------------------------------------------------------------------------------------------ refusals


def _check_options(upsample, max_offset, max_sigma_px, scale, min_correlation, smooth_px) -> int:
    if isinstance(scale, bool) or not isinstance(scale, int | np.integer) or scale < 1:
        raise InputError(f"scale = {scale!r}: must be an integer >= 1 (the pitch of image over reference's)")
    if isinstance(upsample, bool) or not isinstance(upsample, int | np.integer) or not 1 <= upsample <= 1000:
        raise InputError(f"upsample = {upsample!r}: must be an integer in [1, 1000]")
    check_range("max_offset", max_offset, 0.0, 0.5, lo_open=True, error=InputError)
    check_range("max_sigma_px", max_sigma_px, 0.0, None, lo_open=True, error=InputError)
    check_range("min_correlation", min_correlation, 0.0, 1.0, hi_open=True, error=InputError)
    check_range("smooth_px", smooth_px, 0.0, 5.0, error=InputError)
    return int(scale)


def _refuse_featureless(r: np.ndarray, i: np.ndarray, use: np.ndarray) -> None:
    for name, a in (("reference", r), ("image", i)):
        v = a[use]
        if v.size < 64:
            raise InputError(f"{name}: only {v.size} usable pixels (the region less its border, the masked pixels "
                             "and their neighbourhood); at least 64 are needed")  # fmt: skip
        if float(np.ptp(v)) <= 1e-12 * max(1.0, float(np.max(np.abs(v)))):
            raise InputError(f"{name}: the region is flat (no gradient): no offset can be measured")


def _check_offset(name: str, d: np.ndarray, shape, max_offset: float) -> None:
    limit = max_offset * np.array(shape, dtype=float)
    if np.any(np.abs(d) > limit):
        raise InputError(
            f"{name}: offset ({d[0]:.3g}, {d[1]:.3g}) px (ALT, ACT) exceeds max_offset = {max_offset:g} of the "
            f"region's sides {shape} ({limit[0]:.3g}, {limit[1]:.3g} px): register a coarser estimate first, or "
            "give a larger region"
        )


def _check_correlation(rho: float, min_correlation: float) -> None:
    if not abs(rho) >= min_correlation:
        raise InputError(f"image: the aligned regions' correlation {rho:.3g} is below min_correlation = "
                         f"{min_correlation:g}: the images share no content (featureless or unrelated)")  # fmt: skip


def _check_isotropy(jac: np.ndarray) -> None:
    g = jac[:, :2].T @ jac[:, :2]
    ev, vec = np.linalg.eigh(g)
    if not ev[-1] > 0:
        raise InputError("image: the region has no gradient: no offset can be measured")
    if ev[0] < MIN_ISOTROPY * ev[-1]:
        along = math.degrees(math.atan2(abs(vec[0, 0]), abs(vec[1, 0])))
        raise InputError(f"image: the region's gradients run in one direction only (least/largest gradient "
                         f"energy {ev[0] / ev[-1]:.2g} < {MIN_ISOTROPY:g}; e.g. one straight edge): the offset "
                         f"along {along:.0f} deg from ACT is undetermined; include features of other "
                         "orientations")  # fmt: skip


def _check_sigma(cov: np.ndarray, max_sigma_px: float) -> None:
    sig = np.hypot(np.sqrt(np.diag(cov)), FLOOR_PX)
    if not np.all(sig <= max_sigma_px):
        raise InputError(f"image: the offset's 1-sigma ({sig[0]:.3g}, {sig[1]:.3g}) px (ALT, ACT) exceeds "
                         f"max_sigma_px = {max_sigma_px:g}: too little gradient for the noise")  # fmt: skip


# ---------------------------------------------------------------------------------------------- the function


def measure_registration(
    reference,
    image,
    *,
    roi=None,
    mask=None,
    scale: int = 1,
    upsample: int = 20,
    smooth_px: float = SMOOTH_PX,
    max_offset: float = 0.25,
    max_sigma_px: float = 0.5,
    min_correlation: float = 0.2,
) -> RegistrationResult:
    """The subpixel offset of ``image`` from ``reference`` (two bands of one scene), with its 1-sigma.

    Parameters
    ----------
    reference, image : 2-D arrays
        The two bands (numpy masked arrays: their masked pixels are excluded). ``image(y, x) =
        reference(y - dy, x - dx)``: ``offset_px = (dy, dx)`` is ``image``'s content relative to ``reference``'s.
    roi : (x0, y0, x1, y1) or Rect, optional
        The region measured (half-open pixels of the measuring grid, ``image``'s); default: everything.
    mask : bool array or (reference_mask, image_mask), optional
        True = usable (not nodata). One array on one grid; with ``scale > 1`` a pair, each of its image's shape.
    scale : int
        Pitch of ``image`` over that of ``reference`` (4: an MS band against its PAN); ``reference`` is then
        block-averaged over ``image``'s pixel footprints and the offset is in ``image``'s pixels.
    upsample : int
        The phase correlation's subpixel resolution (1 / upsample px), the least squares' start.
    smooth_px : float
        The band limit: the sigma (px) of the Gaussian both images pass before the least squares (0: none).
    max_offset : float
        Largest offset accepted, as a fraction of the region's side (each axis); larger is refused.
    max_sigma_px : float
        Largest 1-sigma accepted (px); a region that fixes the offset less well is refused.
    min_correlation : float
        Least |Pearson correlation| of the aligned regions; below it the images share no content: refused.

    Returns
    -------
    RegistrationResult

    Examples
    --------
    >>> y, x = np.mgrid[0:64, 0:64].astype(float)
    >>> scene = lambda y, x: np.sin(0.3 * x + 0.2 * y) + np.cos(0.25 * x - 0.35 * y)
    >>> r = measure_registration(scene(y, x), scene(y - 0.25, x + 0.5))
    >>> [round(v, 3) for v in r.offset_px]
    [0.25, -0.5]
    """
    scale = _check_options(upsample, max_offset, max_sigma_px, scale, min_correlation, smooth_px)
    r, i, valid = _prepare(reference, image, roi, mask, scale)
    *pc, peak = _phase_correlation(r, i, valid, int(upsample))
    d_pc = np.array(pc)
    _check_offset("image", d_pc, r.shape, max_offset)
    use = _usable(r.shape, valid, d_pc, smooth_px)
    _refuse_featureless(r, i, use)
    if smooth_px > 0:
        r, i = ndi.gaussian_filter(r, smooth_px, mode="mirror"), ndi.gaussian_filter(i, smooth_px, mode="mirror")
    d, a, b, rw, iw, res, jac, n_iter = _gauss_newton(r, i, use, d_pc, min_correlation)
    if float(np.max(np.abs(d - d_pc))) > 1.0 + 1.0 / upsample:
        raise InputError(f"image: the least squares moved {np.max(np.abs(d - d_pc)):.2g} px from the phase "
                         "correlation's peak: the region's content does not fix the offset")  # fmt: skip
    _check_offset("image", d, r.shape, max_offset)
    rho = float(np.corrcoef(rw[use], iw[use])[0, 1])
    _check_correlation(rho, min_correlation)
    cov, s2 = _covariance(jac, res, use, d, smooth_px)
    _check_sigma(cov, max_sigma_px)
    flags = tuple(f for f, on in (("inverted_contrast", a < 0), ("low_correlation", abs(rho) < 0.5),
                                  ("masked", valid is not None)) if on)  # fmt: skip
    return RegistrationResult(
        offset_px=(float(d[0]), float(d[1])), sigma_noise_px=(math.sqrt(cov[0, 0]), math.sqrt(cov[1, 1])),
        sigma_px=(math.hypot(math.sqrt(cov[0, 0]), FLOOR_PX), math.hypot(math.sqrt(cov[1, 1]), FLOOR_PX)),
        covariance_px2=((float(cov[0, 0]), float(cov[0, 1])), (float(cov[1, 0]), float(cov[1, 1]))),
        method=METHOD, correlation=rho, phase_peak=float(peak), gain=a, bias=b, noise_rms=math.sqrt(s2),
        n_pixels=int(use.sum()), usable_fraction=float(use.sum()) / r.size, scale=scale,
        phase_offset_px=(float(d_pc[0]), float(d_pc[1])), iterations=n_iter, flags=flags,
    )  # fmt: skip
