"""Hyperbolic-wedge resolution: the reference paper's contrast scan ("Hyperbolic Wedge Resolution Analysis").

The wedge's stripes narrow along its axis.  At each position along the axis the contrast across the stripes,
``(max - min) / (max + min)`` of the profile across them (optionally averaged over a few neighbouring
positions), is recorded; a linear search from the wide end finds the first position where the contrast
falls to ``threshold`` (15 % by default: the paper's Rayleigh-criterion contrast).  The resolvable *line
width* there is the stripe width (half a period, a "line"); the corresponding frequency is
``1 / (2 line width)`` cycles (line pairs) per px, since bright and dark stripes are equally wide.

Geometry is explicit: ``line_width_px`` gives the stripe width at each position along the axis (the scene
module's truth JSON records it), so the function works on any wedge, hyperbolic or linear.

Validation and uncertainty (issues 10, 18).  The pixel noise is estimated from second differences along the
axis, only where the same row is flat a little further along it (:func:`_noise_std`): sharp converging lines
put many pixels on a moving stripe boundary, which a plain robust sigma read as noise (2-8x), refusing sharp
noise-free wedges.  A region whose wide end has no contrast above the noise (a constant image, no wedge) or
already below the threshold is refused.  The noise-dependent figures come from a parametric bootstrap: the
region with noise of 0.5-3x its variance added (fixed ``seed``: reproducible).  The contrast's 1-sigma
(``contrast_std``) is its spread there.  Noise raises the max and lowers the min of every profile, so the
noisy curve crosses the threshold later than the noise-free one -- by several of its 1-sigma at a contrast
SNR of ~100 without averaging -- and the resolved crossing is corrected for it by SIMEX extrapolation to zero
noise (``resolved_line_width_px_noise_bias``: the correction, raw minus reported); its 1-sigma
(``resolved_*_std``) matches the scatter over noise realisations (benchmarks/bench_wedge_sigma.py: scatter /
sigma 0.6-1.0 on blurred wedges; the old local-residual sigma was 3-10x the scatter, 15-180x in the run).
The deterministic wobble of a noise-free curve near the crossing (sampling phase, aliasing) is not noise: it
is reported apart, ``resolved_line_width_px_sampling_std``, and not added to the 1-sigma.  ``flags`` report
clipping, low contrast-to-noise, a noise floor near the threshold, noisy copies that no longer cross, and a
contrast that climbs back above the threshold after the crossing (spurious resolution / aliasing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._validate import check_choice, check_range
from satchain.errors import InputError
from satchain.measure._clipping import resolve_full_scale
from satchain.measure._common import ResultMixin, clipping_flag, crop_roi, first_crossing, masked_as_nan, robust_sigma
from satchain.units import cy_per_px_to_cy_per_m_ground

__all__ = ["WedgeResult", "measure_wedge"]


@dataclass(frozen=True)
class WedgeResult(ResultMixin):
    """Contrast curve along the wedge and the resolvable line width where it falls to ``threshold``.

    ``position_px`` are positions along the wedge axis (columns for an ``ALT`` wedge, rows for ``ACT``) in the
    region, ordered from the widest stripes; ``line_width_px`` the stripe width there; ``contrast`` the curve.
    The ``resolved_*`` fields are None when the contrast never falls to the threshold; they are corrected for
    the noise bias of the max-min contrast, ``resolved_line_width_px_noise_bias`` (px) being the correction
    (the raw crossing's line width minus the reported one); ``*_std`` are 1-sigma from the noise;
    ``resolved_line_width_px_sampling_std`` the deterministic wobble of the contrast curve near the crossing
    (sampling phase, not noise: not in the 1-sigma); ``noise_std`` the pixel noise estimated; ``flags``
    quality warnings.
    """

    position_px: np.ndarray
    line_width_px: np.ndarray
    contrast: np.ndarray
    threshold: float
    direction: str
    resolved_position_px: float | None
    resolved_line_width_px: float | None
    resolved_f_cy_per_px: float | None
    resolved_line_width_m: float | None = None
    resolved_f_cy_per_m_ground: float | None = None
    contrast_std: np.ndarray | None = None
    resolved_position_px_std: float | None = None
    resolved_line_width_px_std: float | None = None
    resolved_line_width_m_std: float | None = None
    resolved_line_width_px_noise_bias: float | None = None
    resolved_line_width_px_sampling_std: float | None = None
    noise_std: float = 0.0
    flags: tuple = ()


def measure_wedge(
    image,
    *,
    line_width_px,
    direction: str = "ALT",
    roi=None,
    threshold: float = 0.15,
    average_px: int = 1,
    pixel_m: float | None = None,
    valid=None,
    seed: int = 0,
    full_scale: float | None = None,
) -> WedgeResult:
    """Contrast scan along a hyperbolic (or any) wedge; resolvable line width at ``threshold`` contrast.

    Parameters
    ----------
    image : array_like, 2-D
        The image; NaN (nodata) and a numpy masked array's masked pixels are refused inside ``roi``.
    line_width_px : callable or array_like
        Stripe width (px) at each position along the wedge axis: a function of the position (px, in the
        region's coordinates) or an array with one value per position.
    direction : {"ALT", "ACT"}
        Direction *across* the stripes, i.e. the resolution measured.  ``ALT``: stripes run along x, the
        profile is a column, the axis is x (the paper's wedge); ``ACT``: the transpose.
    roi : (x0, y0, x1, y1), optional
        Region holding the stripes only (no surround).
    threshold : float
        Contrast in (0, 1) where the stripes count as no longer resolved.
    average_px : int
        Number of neighbouring profiles averaged at each position (noise reduction).
    pixel_m : float, optional
        Ground sample distance: adds the line width in metres and the frequency in cy/m on the ground.
    valid : array_like of bool, optional
        The image's pixels that belong to the stripes (the image's shape); others (a fill around them) are
        left out of the noise estimate.
    seed : int
        Seed of the noise bootstrap (the 1-sigma and the noise-bias correction); the result is reproducible.
    full_scale : float, optional
        The sensor's full scale in the image's units; integer images default to their dtype maximum.  The
        wedge is flagged ``clipping`` only on evidence: pixels at the full scale, or a flat run at its top
        (bottom) that shows saturation (:func:`satchain.measure.find_clipping`).

    Examples
    --------
    >>> y, x = np.mgrid[0:40, 0:100]
    >>> lw = 6.0 - 0.05 * x  # stripes from 6 px down to 1 px wide
    >>> img = 100 + 80 * np.sign(np.sin(np.pi * y / lw)) * np.clip((x - 50) / -40, 0, 1)
    >>> r = measure_wedge(img, line_width_px=lambda p: 6.0 - 0.05 * p)
    >>> round(r.resolved_position_px, 1), round(r.resolved_line_width_px, 3)
    (42.5, 3.875)
    """
    thr, avg = _check_args(direction, threshold, average_px, seed)
    full_scale = resolve_full_scale(image, full_scale)
    data = crop_roi(masked_as_nan("image", image), roi, min_size=4)  # masked pixels: nodata, refused in the region
    work = data if direction == "ALT" else data.T  # profiles are columns of `work`
    pos, lw = _widths(work, line_width_px)
    keep = _valid_mask(valid, np.shape(image), roi, direction)
    # pixel noise from second differences along the axis where the stripes are flat (see _noise_std)
    noise = _noise_std(work, keep)
    flags = [f for f in [clipping_flag(work, full_scale=full_scale, noise_std=noise)] if f]
    order = np.argsort(-lw, kind="stable")  # from the widest stripes
    hi, lo = _levels(work, avg)
    if np.any(hi + lo <= 0):
        raise InputError("image: contrast needs positive levels (max + min > 0) in every profile")
    contrast = ((hi - lo) / (hi + lo))[order]
    pos, lw = pos[order], lw[order]
    boot = _Bootstrap.run(work, avg, noise, order, thr, np.random.default_rng(seed))
    c_std = boot.contrast_std
    c_noise = _noise_contrast(noise, avg, work.shape[0], hi + lo)
    _check_wide_end(contrast, c_std, c_noise, thr, flags)
    cross = _resolved(boot, pos, lw, contrast, thr, flags)
    if c_noise > 0.5 * thr:
        flags.append(f"noise floor: pure noise alone gives a contrast of ~{c_noise:.3f} (threshold {thr:g})")
    res_pos, res_lw, res_f, sd_pos, sd_lw, bias_lw, smp_lw = cross
    return WedgeResult(
        position_px=pos,
        line_width_px=lw,
        contrast=contrast,
        threshold=thr,
        direction=direction,
        resolved_position_px=res_pos,
        resolved_line_width_px=res_lw,
        resolved_f_cy_per_px=res_f,
        resolved_line_width_m=None if (pixel_m is None or res_lw is None) else res_lw * pixel_m,
        resolved_f_cy_per_m_ground=(
            None if (pixel_m is None or res_f is None) else float(cy_per_px_to_cy_per_m_ground(res_f, gsd_m=pixel_m))
        ),
        contrast_std=c_std,
        resolved_position_px_std=sd_pos,
        resolved_line_width_px_std=sd_lw,
        resolved_line_width_m_std=None if (pixel_m is None or sd_lw is None) else sd_lw * pixel_m,
        resolved_line_width_px_noise_bias=bias_lw,
        resolved_line_width_px_sampling_std=smp_lw,
        noise_std=noise,
        flags=tuple(flags),
    )


def _check_args(direction, threshold, average_px, seed) -> tuple[float, int]:
    """The checked options of :func:`measure_wedge`: (threshold, average_px)."""
    check_choice("direction", direction, ("ALT", "ACT"))
    thr = check_range("threshold", threshold, 0.0, 1.0, lo_open=True, hi_open=True)
    avg = int(check_range("average_px", average_px, 1, 1000))
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed = {seed!r}: must be a non-negative integer")
    return thr, avg


def _widths(work: np.ndarray, line_width_px) -> tuple[np.ndarray, np.ndarray]:
    """Positions along the wedge axis and the stripe width (px) at each (checked)."""
    pos = np.arange(work.shape[1], dtype=float)
    lw = np.asarray(line_width_px(pos) if callable(line_width_px) else line_width_px, dtype=float)
    if lw.shape != pos.shape or not np.all(np.isfinite(lw)) or np.any(lw <= 0):
        raise InputError(
            f"line_width_px: need {pos.size} finite positive widths (one per position along the wedge), "
            f"got shape {lw.shape}"
        )
    return pos, lw


def _noise_contrast(noise: float, avg: int, n_rows: int, level_sum: np.ndarray) -> float:
    """The contrast pure noise gives: the expected range of ``n_rows`` noisy values over the median max + min."""
    s_eff = noise / np.sqrt(avg)
    return 2 * s_eff * np.sqrt(2 * np.log(max(n_rows, 2))) / float(np.median(level_sum))


def _resolved(boot, pos, lw, contrast, thr: float, flags: list) -> tuple:
    """Where the contrast (ordered from the widest stripes) first falls to ``thr``: (position, line width,
    frequency, their 1-sigma in position and line width, the noise bias removed from the line width, the
    sampling wobble of the line width), all None where it never does (flagged)."""
    c_std = boot.contrast_std
    idx = np.arange(pos.size, dtype=float)
    p_raw = first_crossing(idx, contrast, thr)
    if p_raw is None:
        flags.append("the contrast never falls to the threshold in this region")
        return (None,) * 7
    p_res, sd_idx, bias_idx = boot.crossing(p_raw, idx[-1], flags)
    res_pos = float(np.interp(p_res, idx, pos))
    res_lw = float(np.interp(p_res, idx, lw))
    res_f = 1.0 / (2.0 * res_lw)
    step = np.abs(np.interp(p_res, idx, np.gradient(pos))), np.abs(np.interp(p_res, idx, np.gradient(lw)))
    sd_pos, sd_lw = float(sd_idx * step[0]), float(sd_idx * step[1])
    bias_lw = float(np.interp(p_raw, idx, lw) - res_lw)
    smp_lw = float(_sampling_std(idx, contrast, c_std, p_raw) * step[1])
    after = contrast[int(np.ceil(p_raw)) + 2 :]
    if after.size and np.max(after - 2 * c_std[int(np.ceil(p_raw)) + 2 :]) > thr:
        flags.append("the contrast climbs back above the threshold after the crossing (spurious resolution)")
    return res_pos, res_lw, res_f, sd_pos, sd_lw, bias_lw, smp_lw


def _check_wide_end(contrast, c_std, c_noise: float, thr: float, flags: list) -> None:
    """Refuse a region without a wedge (no contrast above the noise at the wide end) or one whose wide end is
    already below the threshold; flag a low contrast-to-noise."""
    wide = float(np.median(contrast[: min(5, contrast.size)]))
    sd = float(np.median(c_std[: min(5, contrast.size)]))
    if not (wide > 3 * c_noise and wide > 5 * sd and wide > 0):
        raise InputError(
            f"image: no wedge: the contrast at the wide end ({wide:.3g}) is not above the noise "
            f"(noise contrast ~{c_noise:.2g}); a constant or stripe-free region"
        )
    if wide <= thr:
        raise InputError(
            f"threshold = {thr:g}: the contrast at the wide end is already {wide:.3g}; no resolution to find "
            "(a blurred or wrongly framed wedge)"
        )
    if sd > 0 and wide / sd < 10:
        flags.append(f"low contrast-to-noise: wide-end contrast / its 1-sigma = {wide / sd:.1f} < 10")


#: the flatness test of the noise estimate: a neighbourhood range below this many noise sigmas counts as flat
FLAT_RANGE_SIGMA = 3.0
#: noisy copies per noise level in the crossing's parametric bootstrap
N_BOOT = 32
#: added noise variances (in units of the image's) of the bootstrap: total noise sqrt(1 + lambda) sigma
BOOT_LAMBDA = (0.5, 1.0, 2.0, 3.0)
#: the SIMEX extrapolant: crossing = a + b (total noise)^BIAS_POWER (1: a plateau's maximum; 2: one peak's)
BIAS_POWER = 1.5


def _valid_mask(valid, shape: tuple, roi, direction: str) -> np.ndarray | None:
    """The ``valid`` pixels (image shape) cropped to the region and laid out as ``work`` (profiles = columns)."""
    if valid is None:
        return None
    v = np.asarray(valid)
    if v.shape != tuple(shape):
        raise InputError(f"valid: need a boolean mask of the image's shape {tuple(shape)}, got shape {v.shape}")
    v = crop_roi(v.astype(float), roi, name="valid", min_size=1) > 0.5
    return v if direction == "ALT" else v.T


def _noise_std(work: np.ndarray, keep: np.ndarray | None) -> float:
    """Pixel noise (1-sigma) from second differences along the wedge axis on the flat parts of the image.

    ``h = x[i, j-1] - 2 x[i, j] + x[i, j+1]`` (variance ``6 sigma^2`` for white noise) is zero on a noise-free
    stripe interior, but not where a sharp stripe boundary moves through the pixel: converging lines put many
    pixels there, and a robust sigma of all ``h`` then reads the stripes as noise (up to 5x on sharp wedges).
    ``h`` is therefore used only where the same row is flat a little further along the axis: the range of
    ``x[i, j-3], x[i, j-2], x[i, j+2], x[i, j+3]`` at most ``FLAT_RANGE_SIGMA`` sigma. A boundary that crosses
    row ``i`` between ``j-1`` and ``j+1`` changes that row's value between ``j-2`` and ``j+2``, so it fails the
    test; the test uses other pixels than ``h``, so it does not select on ``h``'s own noise. Sigma is
    iterated from the robust sigma of all ``h`` (1.4826 MAD / sqrt 6) to a fixed point. Stripe interiors of a
    sharp wedge and the washed-out narrow end of a blurred one are flat; a noise-free wedge gives ~0. Pixels
    outside ``keep`` (a fill around the stripes) are left out.
    """
    ny, nx = work.shape
    if nx < 3:
        return 0.0
    if nx < 7:
        return float(robust_sigma(np.diff(work, n=2, axis=1)) / np.sqrt(6))
    j = np.arange(3, nx - 3)
    h = work[:, j - 1] - 2 * work[:, j] + work[:, j + 1]
    near = np.stack([work[:, j - 3], work[:, j - 2], work[:, j + 2], work[:, j + 3]])
    spread = near.max(axis=0) - near.min(axis=0)
    ok = np.ones(h.shape, bool) if keep is None else np.all([keep[:, j + d] for d in range(-3, 4)], axis=0)
    if not ok.any():
        ok = np.ones(h.shape, bool)
    sigma = robust_sigma(h[ok]) / np.sqrt(6)
    floor = 1e-9 * float(np.ptp(work))
    for _ in range(10):
        sel = ok & (spread <= max(FLAT_RANGE_SIGMA * sigma, floor))
        if np.count_nonzero(sel) < min(50, h[ok].size // 4 + 1):
            break
        new = robust_sigma(h[sel]) / np.sqrt(6)
        converged = abs(new - sigma) <= 1e-3 * sigma
        sigma = new
        if converged:
            break
    return float(sigma)


def _levels(work: np.ndarray, avg: int) -> tuple[np.ndarray, np.ndarray]:
    """Max and min of each profile (axis -2) after averaging ``avg`` neighbouring profiles (axis -1; zero
    padded at the ends as ``np.convolve(..., mode="same")``: both levels scale, the contrast does not)."""
    if avg > 1:
        from scipy.ndimage import convolve1d

        work = convolve1d(work, np.ones(avg) / avg, axis=-1, mode="constant", origin=-1 if avg % 2 == 0 else 0)
    return work.max(axis=-2), work.min(axis=-2)


@dataclass(frozen=True)
class _Bootstrap:
    """Contrast curves of noisy copies of the region (parametric bootstrap) at each added noise level."""

    contrast: tuple  # per level of BOOT_LAMBDA: (N_BOOT, n_pos) ordered from the widest stripes
    contrast_std: np.ndarray
    thr: float

    @classmethod
    def run(cls, work, avg: int, noise: float, order, thr: float, rng: np.random.Generator) -> _Bootstrap:
        n_pos = work.shape[1]
        if noise <= 0:
            return cls((), np.zeros(n_pos), thr)
        curves = []
        for lam in BOOT_LAMBDA:
            c = np.empty((N_BOOT, n_pos))
            for k in range(0, N_BOOT, 8):  # a few copies at a time: bounded memory on large regions
                m = min(8, N_BOOT - k)
                hi, lo = _levels(work + noise * np.sqrt(lam) * rng.standard_normal((m, *work.shape)), avg)
                c[k : k + m] = ((hi - lo) / np.where(hi + lo > 0, hi + lo, np.inf))[:, order]
            curves.append(c)
        return cls(tuple(curves), np.std(curves[0], axis=0, ddof=1), thr)

    def crossing(self, p_raw: float, last: float, flags: list) -> tuple[float, float, float]:
        """(crossing corrected for the noise bias, its 1-sigma, the bias removed), in positions.

        Noise raises the max and lowers the min of every profile, so a noisy contrast curve crosses the
        threshold later than the noise-free one: by several of its 1-sigma at a contrast SNR of ~100 without
        averaging. SIMEX (Cook & Stefanski 1994, JASA 89, 1314): the mean crossing of the copies at total noise
        ``s = sqrt(1 + lambda)`` sigma, with the observed one at ``s = 1``, is fitted by ``a + b s^1.5`` and
        extrapolated to ``s = 0``. The bias of a maximum of noisy pixels grows as ``s`` for many equal pixels
        and as ``s^2`` for one clearly highest; the power 1.5 between them leaves at most ~1 sigma of the bias
        on exact renders of sharp and blurred wedges (benchmarks/bench_wedge_sigma.py). The 1-sigma is the
        spread of the crossing in the copies at ``lambda = 0.5`` (close to the spread over noise realisations)
        times ``sqrt(sum_k w_k^2 (1 + lambda_k))``, the extrapolation's weights ``w_k`` applied to independent
        crossings whose variance grows with the noise variance.
        """
        if not self.contrast:
            return p_raw, 0.0, 0.0
        idx = np.arange(self.contrast[0].shape[1], dtype=float)
        found = []
        for c in self.contrast:
            xs = [first_crossing(idx, row, self.thr) for row in c]
            found.append(np.array([x for x in xs if x is not None], dtype=float))
        sd = float(np.std(found[0], ddof=1)) if found[0].size > 1 else float("nan")
        if any(f.size < N_BOOT // 2 for f in found):
            flags.append("noise: most noisy copies never cross the threshold; crossing not corrected for noise bias")
            return p_raw, sd, 0.0
        lam = np.array([0.0, *BOOT_LAMBDA])
        means = np.array([p_raw, *(float(np.mean(f)) for f in found)])
        w = np.linalg.pinv(np.vstack([np.ones(lam.size), (1.0 + lam) ** (BIAS_POWER / 2)]).T)[0]  # a at s = 0
        p_res = float(np.clip(w @ means, 0.0, last))
        return p_res, sd * float(np.sqrt(np.sum(w**2 * (1.0 + lam)))), p_raw - p_res


def _sampling_std(idx, contrast, c_std, p_res: float) -> float:
    """Deterministic wobble of the contrast curve about a straight line near the crossing (+-5 positions),
    over its slope, in positions: the sampling phase and aliasing of a noise-free curve, not noise (the noise
    variance is removed). A hint of how much the crossing depends on where the stripes fall on the pixels."""
    sel = np.abs(idx - p_res) <= 5
    if np.count_nonzero(sel) < 3:
        return float("nan")
    slope, icpt = np.polyfit(idx[sel], contrast[sel], 1)
    resid = contrast[sel] - (slope * idx[sel] + icpt)
    dof = max(np.count_nonzero(sel) - 2, 1)
    var = float(np.sum(resid**2) / dof - np.mean(c_std[sel] ** 2))
    return float(np.sqrt(max(var, 0.0)) / abs(slope)) if slope != 0 else float("inf")
