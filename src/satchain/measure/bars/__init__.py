"""Bar-target CTF and the MTF derived from it by the inverse Coltman series.

Each bar group is a square wave of known period (``periods_px``, one bright + one dark bar).  Its profile
across the bars is averaged along the bars and fitted, by least squares at the known period, with the
blurred square wave's Fourier series ``a + sum_k A_k cos(2 pi k (x - x0) / P)`` (odd ``k``; the phase
``x0`` free, so the result does not depend on where the bars fall on the pixel grid).  Harmonics above the
sampling Nyquist are fitted at their true frequency -- the samples are exact values of the continuous
profile, so an aliased harmonic is identifiable as long as its folded frequency differs from the others'.
The contrast transfer is the modulation of the fitted continuous profile between a bar centre and a gap
centre, ``|sum_k A_k| / a`` (Coltman's definition), divided by the large-area contrast of the target
(``(bright - dark) / (bright + dark)`` of large uniform areas).  Each CTF carries a 1-sigma from the noise
(estimated from the rows along the bars, or from the fit residual) propagated through the fit.

Validation.  A group must cover 1.5 periods, its profile's dominant period must be the claimed one, the
periodic model must explain the profile, and the fitted modulation must stand above the noise; otherwise
the group is refused: alone in a target of two or more groups (``BarsResult.refused`` and a flag give the
reason, its CTF and MTF are NaN, the other groups are measured), the call for a lone group.  In a target of
two or more groups a modulation that does not stand above the noise is a measurement at the noise floor
(flagged ``at_noise_floor``: CTF ~0 with its 1-sigma, uncorrected), unless another period stands out in the
region or the profile is not noise about a level (``_bargroups``).  Without
``levels`` the large-area levels are the plateaus of the widest group (its samples near bar and gap
centres), only if they are flat at every grid phase (else refused: the CTF would be inflated, the old
default's 7.8 %; a long-tailed PSF holds even flat-looking tops below the levels, see
:func:`satchain.measure.bars._fit.plateau`); a single group cannot be its own reference.  The fitted CTF is
kept within [the samples' own modulation, 1] (a lower bound, and the bound of a non-negative PSF), flagged
when clipped.  Where a group's samples within P/8 of its bar and gap centres are flat (wide bars), their
means are the peak and trough themselves and give the CTF directly (no truncated series).

Targets of three or more groups (``_barjoint``, ``_barfinite``).  One group's samples cannot tell every
harmonic apart (at 4 px harmonic 3 folds onto the fundamental; at some phases its samples are exactly those
of another MTF), and a finite group is not Coltman's infinite square wave (a long-tailed PSF lifts a grating's
troughs more: +0.01-0.02 for an obscured pupil).  All groups share one MTF: a model of it (pixel sinc x a
smooth optics term, with the measured points' residuals interpolated) is fitted to the groups' observed
harmonics; the harmonics a group cannot observe are held at it (iterated to a fixed point); then each group is
rendered exactly as it lies in its region through the model and measured by the same estimator, and the
difference from the model's Coltman CTF is added (``ctf_correction``; its model uncertainty is in
``ctf_std``).  The reported CTF is then the square-wave CTF that the inverse series and a prediction use:
within 0.022 of Coltman's at every phase and period from 2.5 to 12 px for Gaussian and obscured-pupil systems
(``benchmarks/bench_targets.py``).  A lone group keeps its flags.  ``bars_per_group`` (3 by default) gives
the group's length; ``None`` (a long grating) applies no finite-group correction.

Levels.  The CTF is relative to the large-area contrast, so an error of the image's offset (in the units the
levels are given in) moves every CTF: an offset ``e`` too large lowers a group's mean level ``a`` and raises its
CTF by ``e / a``.  The positive residuals of the default ``satchain run`` (+0.005 to +0.013 without noise) are
of this kind: ``measure auto`` calibrates the image on the medians of finite uniform areas, which the long
diffraction tail pulls toward their surroundings (``benchmarks/bench_bar_residuals.py``); with the sensor's
true response the residuals are +0.001 to +0.003, the bar targets' 2-D geometry (bars five widths long).

The MTF at the group frequencies follows from Coltman (1954)'s inverse series, applied here to the measured,
discrete CTF (linear interpolation between groups, zero above the highest measured frequency; so the groups
should reach the frequency where the CTF vanishes). ``satchain.tf.ctf`` has the same series for continuous CTF
functions; this module keeps its own so measurement stays independent of prediction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._validate import check_choice, check_positive
from satchain.errors import InputError
from satchain.measure._clipping import resolve_full_scale
from satchain.measure._common import ResultMixin, masked_as_nan
from satchain.measure.bars._finite import finite_group_correction
from satchain.measure.bars._fit import GroupFit
from satchain.measure.bars._fit import plateau as _plateau
from satchain.measure.bars._groups import Groups, measure_groups, refusal_flags, renumber, scatter, validate_deferred
from satchain.measure.bars._joint import fit_mtf_model, held_harmonics, prior_harmonics, refit_with_prior
from satchain.units import cy_per_px_to_cy_per_m_ground

__all__ = ["BarsResult", "measure_bars", "coltman_inverse_coefficients", "mtf_from_ctf_samples"]


@dataclass(frozen=True)
class BarsResult(ResultMixin):
    """CTF per bar group and the MTF from the inverse Coltman series, at ``f_cy_per_px = 1 / period``.

    ``ctf_std`` / ``mtf_std`` are 1-sigma (noise); ``phase_px`` the fitted position of a bar centre in each
    group's region (px along the profile); ``noise_std`` the profile noise per group; ``flags`` warnings.
    MTF values outside [0, 1.2] (noise in the inverse series) are reported as NaN and flagged.
    ``ctf_correction`` is what the target's joint MTF added to each group's measured modulation to give the
    square-wave CTF (None: fewer than three groups, or ``bars_per_group=None``).  ``refused`` lists
    ``(index, reason)`` of the groups refused alone (their CTF and MTF are NaN; the others are measured).
    """

    f_cy_per_px: np.ndarray
    periods_px: np.ndarray
    ctf: np.ndarray
    mtf: np.ndarray
    large_area_contrast: float
    direction: str
    f_cy_per_m_ground: np.ndarray | None = None
    ctf_std: np.ndarray | None = None
    mtf_std: np.ndarray | None = None
    phase_px: np.ndarray | None = None
    large_area_contrast_std: float = 0.0
    levels_from: str = "given"
    noise_std: np.ndarray | None = None
    flags: tuple = ()
    ctf_correction: np.ndarray | None = None
    refused: tuple = ()


def coltman_inverse_coefficients(n_terms: int = 40) -> list[tuple[int, float]]:
    """``(k, B_k)`` of MTF(f) = (pi / 4) sum_k B_k CTF(k f), odd k (Coltman 1954).

    ``B_k = 0`` if ``k`` has a squared prime factor, else ``(-1)^m (-1)^((k-1)/2) / k`` with ``m`` its number
    of prime factors: 1, +1/3, -1/5, +1/7, 0, +1/11, -1/13, -1/15, ...

    Examples
    --------
    >>> [(k, round(b, 4)) for k, b in coltman_inverse_coefficients(5)]
    [(1, 1.0), (3, 0.3333), (5, -0.2), (7, 0.1429)]
    """
    out = []
    for k in range(1, 2 * n_terms, 2):
        m, rest, square = 0, k, False
        p = 3
        while p * p <= rest:
            if rest % p == 0:
                rest //= p
                m += 1
                if rest % p == 0:
                    square = True
                    break
            else:
                p += 2
        if square:
            continue
        if rest > 1:
            m += 1
        out.append((k, (-1) ** m * (-1) ** ((k - 1) // 2) / k))
    return out


def mtf_from_ctf_samples(f_cy_per_px, ctf, *, n_terms: int = 40) -> np.ndarray:
    """Inverse Coltman series on discrete CTF samples (linear interpolation, 0 beyond the last sample).

    Examples
    --------
    >>> f = np.array([0.2, 0.4])
    >>> np.round(mtf_from_ctf_samples(f, 4 / np.pi * np.array([0.5, 0.0])), 3) + 0.0  # -0.0 printed as 0.0
    array([0.5, 0. ])
    >>> mtf_from_ctf_samples([], []).size  # no usable group (a run whose bars were all refused)
    0
    """
    f = np.asarray(f_cy_per_px, dtype=float)
    c = np.asarray(ctf, dtype=float)
    if f.size == 0:  # no usable group: no MTF
        return np.zeros(0)
    order = np.argsort(f)
    fs, cs = f[order], c[order]
    out = np.zeros_like(f)
    for k, b in coltman_inverse_coefficients(n_terms):
        out += b * np.interp(k * f, fs, cs, right=0.0)
    return np.pi / 4 * out


#: Largest CTF reported; anything above is refused (levels wrong, or not bars).
CTF_MAX = 1.2


def _sampled_floor(prof: np.ndarray, noise: float) -> float:
    """Modulation of the samples themselves, less twice the expected noise excess of a max - min: a lower
    bound of the continuous profile's modulation (the samples are values of it)."""
    z = np.sqrt(2 * np.log(max(prof.size, 2)))
    span = float(prof.max() - prof.min()) - 2 * z * (noise if np.isfinite(noise) else 0.0)
    return max(span, 0.0) / float(prof.max() + prof.min())


def _bounded_ctf(ctf, mod_std, c_large, c_std, floor, periods, flags, extra_std=0.0):
    """The fitted CTF kept within [sampled modulation, 1]: the samples bound it from below, and a blurred
    profile (non-negative PSF) stays within the target's levels.  A fit outside (aliased harmonics of a
    sharp system) is clipped and flagged."""
    ctf = np.asarray(ctf, dtype=float).copy()
    std = np.sqrt((mod_std / c_large) ** 2 + (ctf * c_std / c_large) ** 2 + np.asarray(extra_std) ** 2)
    for i in range(ctf.size):
        lo, hi = floor[i], 1.0
        if ctf[i] < lo - max(2 * std[i], 0.005):
            flags.append(f"group {i}: fitted CTF {ctf[i]:.3f} below the sampled modulation: raised to {lo:.3f}")
            std[i] = max(std[i], ctf[i] - lo)
            ctf[i] = lo
        elif ctf[i] > hi + max(2 * std[i], 0.01):
            flags.append(
                f"group {i}: fitted CTF {ctf[i]:.3f} > 1 (harmonics of a sharp system aliased at "
                f"{periods[i]:g} px): clipped to 1, the bound of a non-negative PSF"
            )
            std[i] = max(std[i], abs(1.0 - max(lo, 0.0)) / 2)
            ctf[i] = hi
    return ctf, std


def _levels(fits, periods, levels, profiles, noises=None):
    """Large-area contrast, its 1-sigma and where it came from."""
    if levels is not None:
        dark, bright = (float(v) for v in levels)
        if not (bright > dark and bright + dark > 0):
            raise InputError(f"levels = ({dark:g}, {bright:g}): need bright > dark and a positive mean")
        return (bright - dark) / (bright + dark), 0.0, "given"
    if len(fits) < 2:
        raise InputError(
            "levels: not given and only one group: a group cannot be its own reference; give the large-area "
            "(dark, bright) levels"
        )
    i = int(np.argmax(periods))
    return _plateau_contrast(profiles[i], fits[i], float(periods[i]), None if noises is None else noises[i])


def _plateau_contrast(prof: np.ndarray, fit: GroupFit, period: float, noise: float | None = None):
    """Large-area contrast from the widest group's plateaus; refused when it has none (the CTF would be
    inflated)."""
    found, spread = _plateau(prof, fit, period, noise=_rows_noise(noise))
    if found is None:
        raise InputError(
            f"levels: not given, and the widest group (period {period:g} px) has no flat bar tops (period under "
            f"8 px, or tops dropping by {spread:.1%} of the amplitude within P/8 of a bar or gap centre, over 0.5 %: "
            "a blur too wide for the bars, or a long-tailed PSF such as diffraction, which also holds the tops "
            "below the large-area levels): its modulation is below the large-area contrast and would inflate every "
            "CTF; give the (dark, bright) levels"
        )
    return found[0], found[1], f"plateaus of the widest group (period {period:g} px)"


def measure_bars(
    image,
    *,
    periods_px,
    group_rois,
    direction: str = "ACT",
    levels=None,
    pixel_m: float | None = None,
    bars_per_group: int | None = 3,
    full_scale: float | None = None,
) -> BarsResult:
    """CTF of bar groups (fitted at the known period, any grid phase) and the MTF from the inverse Coltman
    series.

    Parameters
    ----------
    image : array_like, 2-D
        The image; a group whose region holds NaN (nodata) or a numpy masked array's masked pixels is refused.
    periods_px : sequence of float
        Period (bright + dark bar) of each group, px (>= 2).
    group_rois : sequence of (x0, y0, x1, y1)
        One region per group, covering whole bars (at least 1.5 periods across them) and no plate around
        them (e.g. from the first to the last bar centre).
    direction : {"ACT", "ALT"}
        ``ACT``: bars parallel to y, profile along x (the ACT CTF); ``ALT``: bars parallel to x.
    levels : (dark, bright), optional
        Large-area dark and bright levels.  By default the plateaus of the widest group, which must then be
        flat-topped (refused otherwise) and be one of at least two groups.
    pixel_m : float, optional
        Ground sample distance; adds ``f_cy_per_m_ground``.
    bars_per_group : int or None
        Bright bars in each group (3: USAF-style and the paper's targets), for the finite-group correction of a
        target of three or more groups; ``None``: long gratings, no correction.
    full_scale : float, optional
        The sensor's full scale in the image's units; integer images default to their dtype maximum.  A group
        is flagged ``clipping`` only on evidence: pixels at the full scale, or a flat run at its top (bottom)
        that shows saturation (:func:`satchain.measure.find_clipping`), never for its own maximum.

    Raises
    ------
    InputError
        A region with no bars at its period (another period dominates, the modulation of a lone group is not
        above the noise, or the profile is not periodic: a single bar or edge), a target with no group above
        the noise, default levels that cannot be trusted, or a CTF above 1.2.

    Examples
    --------
    A grating blurred down to its fundamental, bars off the pixel grid: modulation 37.5 / 125 = 0.3 over the
    large-area contrast 0.6.

    >>> x = np.arange(64.0)
    >>> img = np.tile(125 + 37.5 * np.cos(2 * np.pi * (x - 1.3) / 8), (20, 1))
    >>> r = measure_bars(img, periods_px=[8.0], group_rois=[(0, 0, 64, 20)], levels=(50.0, 200.0))
    >>> round(float(r.ctf[0]), 3), round(float(r.phase_px[0]), 3)
    (0.5, 1.3)
    """
    periods = _check_args(periods_px, group_rois, direction, bars_per_group)
    fs = resolve_full_scale(image, full_scale)
    groups = measure_groups(masked_as_nan("image", image), periods, group_rois, direction, fs)  # masked: nodata
    kept = [i for i in range(periods.size) if i not in groups.refused]
    t = _target_ctf(groups, kept, periods, levels, bars_per_group)
    for j, msg in t.deferred_refused.items():  # refused against the target's MTF model
        groups.refused[kept[j]] = msg
    keep = np.array([i not in groups.refused for i in range(periods.size)])
    ctf, ctf_std = scatter(t.ctf, kept, periods.size), scatter(t.ctf_std, kept, periods.size)
    ctf[~keep], ctf_std[~keep] = np.nan, np.nan
    f = 1.0 / periods
    mtf, mtf_std = np.full(f.size, np.nan), np.full(f.size, np.nan)
    mtf[keep], mtf_std[keep] = _mtf_with_std(f[keep], ctf[keep], ctf_std[keep])
    flags = renumber(t.flags, kept) + refusal_flags(groups.refused)
    bad = keep & ~((mtf >= 0) & (mtf <= CTF_MAX))
    if np.any(bad):
        flags.append(f"MTF outside [0, {CTF_MAX}] at {np.round(f[bad], 4).tolist()} cy/px (noise): set to NaN")
        mtf = np.where(bad, np.nan, mtf)
    return BarsResult(
        f_cy_per_px=f,
        periods_px=periods,
        ctf=ctf,
        mtf=mtf,
        large_area_contrast=float(t.c_large),
        direction=direction,
        f_cy_per_m_ground=None if pixel_m is None else cy_per_px_to_cy_per_m_ground(f, gsd_m=pixel_m),
        ctf_std=ctf_std,
        mtf_std=mtf_std,
        phase_px=np.where(keep, scatter(t.phase, kept, periods.size), np.nan),
        large_area_contrast_std=float(t.c_std),
        levels_from=t.levels_from,
        noise_std=np.where(keep, scatter(t.noise, kept, periods.size), np.nan),
        flags=tuple(flags),
        ctf_correction=None if t.corr is None else np.where(keep, scatter(t.corr, kept, periods.size), np.nan),
        refused=tuple(sorted(groups.refused.items())),
    )


def _check_args(periods_px, group_rois, direction, bars_per_group) -> np.ndarray:
    """The checked options of :func:`measure_bars`: the periods (px)."""
    check_choice("direction", direction, ("ACT", "ALT"))
    if bars_per_group is not None and (
        isinstance(bars_per_group, bool) or int(bars_per_group) != bars_per_group or bars_per_group < 2
    ):
        raise InputError(
            f"bars_per_group = {bars_per_group!r}: need a whole number >= 2 (bright bars per group), or None for a "
            "long grating"
        )
    periods = np.array([check_positive("periods_px", p) for p in periods_px], dtype=float)
    if len(group_rois) != periods.size or periods.size == 0:
        raise InputError(f"group_rois: {len(group_rois)} regions for {periods.size} periods; need one per group")
    if np.any(periods < 2.0):
        raise InputError(f"periods_px = {periods.tolist()}: every period must be >= 2 px (Nyquist)")
    return periods


@dataclass
class _TargetCtf:
    ctf: np.ndarray
    ctf_std: np.ndarray
    phase: np.ndarray
    noise: np.ndarray
    corr: np.ndarray | None
    c_large: float
    c_std: float
    levels_from: str
    flags: list
    deferred_refused: dict


def _target_ctf(groups: Groups, kept, periods_all, levels, bars_per_group) -> _TargetCtf:
    """CTF of the kept groups (indices 0..k-1 here, in ``kept`` order): levels, joint MTF model, plateaus,
    finite-group correction, bounds."""
    periods = periods_all[np.asarray(kept, dtype=int)]
    fits = [groups.fits[i] for i in kept]
    profiles = [groups.profiles[i] for i in kept]
    noises = [groups.noises[i] for i in kept]
    flags = [_local(f, i, j) for j, i in enumerate(kept) for f in groups.flags[i]]
    deferred = {j: groups.deferred[i] for j, i in enumerate(kept) if i in groups.deferred}  # caller's numbering
    floors = [_sampled_floor(prof, fit.noise) for prof, fit in zip(profiles, fits, strict=True)]
    c_large, c_std, levels_from = _levels(fits, periods, levels, profiles, noises)
    fits, flags, model, joint = _fill_unobserved(fits, profiles, noises, periods, c_large, flags)
    mod = np.array([ft.modulation for ft in fits])
    mod_std = np.array([ft.modulation_std for ft in fits])
    plateau = np.zeros(len(fits), dtype=bool)
    floor = [j for j, i in enumerate(kept) if i in groups.floor]  # at the noise floor: the fit's modulation as is
    for i, (prof, fit, p) in enumerate(zip(profiles, fits, periods, strict=True)):
        if i in floor:
            continue
        found, _ = _plateau(prof, fit, float(p), noise=_rows_noise(noises[i]))
        if found is not None:  # flat bar tops: the samples are the peak and trough (no series truncation)
            mod[i], mod_std[i] = found
            plateau[i] = True
            flags = [f for f in flags if not (f.startswith(f"group {i}: ") and "alias" in f)]
    corr, corr_std = np.zeros(len(fits)), np.zeros(len(fits))
    if model is not None and bars_per_group is not None:
        corr, corr_std, flags = finite_group_correction(
            model, fits, profiles, periods, c_large, int(bars_per_group), joint, plateau, flags
        )
        corr[floor], corr_std[floor] = 0.0, 0.0  # no bars seen to render: nothing to correct
        flags = [f for f in flags if not _correction_flag_of(f, floor)]
    elif bars_per_group is not None:
        flags.append(
            f"fewer than 3 groups with a measurable fundamental: each CTF is that of its finite {bars_per_group}-bar "
            "group as sampled, not corrected to the square-wave (Coltman) CTF; for a long-tailed PSF (diffraction) "
            "or a sharp system they can differ by a few %"
        )
    refused = {}
    if deferred:
        flags, refused = validate_deferred(deferred, model, fits, profiles, periods, c_large, bars_per_group, flags)
    floor = np.array(floors) / c_large
    if np.nanmax(floor) > CTF_MAX:
        k = int(np.nanargmax(floor))
        raise InputError(
            f"levels = {levels!r}: the sampled CTF of the {periods[k]:g} px group is already {floor[k]:.3g} > "
            f"{CTF_MAX}; the large-area contrast is too small (wrong levels?)"
        )
    ctf, ctf_std = _bounded_ctf(mod / c_large + corr, mod_std, c_large, c_std, floor, periods, flags, corr_std)
    return _TargetCtf(
        ctf,
        ctf_std,
        np.array([ft.x0 for ft in fits]),
        np.array([ft.noise for ft in fits]),
        corr if model is not None and bars_per_group is not None else None,
        float(c_large),
        float(c_std),
        levels_from,
        flags,
        refused,
    )


def _correction_flag_of(flag: str, groups) -> bool:
    """A square-wave correction's flag (applied, or not for the region) of one of ``groups``."""
    starts = any(flag.startswith(f"group {j}: CTF corrected") or flag.startswith(f"group {j}: its region")
                 for j in groups)  # fmt: skip
    return bool(starts)


def _rows_noise(noise) -> float | None:
    """The rows' noise of a profile (None: a single row, no noise estimate: the fit residual is used)."""
    return None if noise is None else float(noise)


def _local(msg: str, i: int, j: int) -> str:
    """A group's message numbered ``i`` (the caller's index) renumbered ``j`` (its place among the kept)."""
    return msg.replace(f"group {i}: ", f"group {j}: ", 1).replace(f"group_rois[{i}]", f"group_rois[{j}]")


def _fill_unobserved(fits, profiles, noises, periods, c_large, flags):
    """Groups with harmonics they cannot observe (aliased onto fitted ones, or sampled at their zero
    crossings): refit with the target's joint MTF model as a prior on those harmonics, iterated with the
    model to a fixed point (needs enough groups; else each group keeps its flag).  See ``_barjoint``."""
    todo = [
        i
        for i, (ft, p, prof) in enumerate(zip(fits, periods, profiles, strict=True))
        if _joint_candidate(ft, float(p), len(prof))
    ]
    first, fits, used = fits, list(fits), {}
    model = fit_mtf_model(fits, periods, c_large)
    if model is None or not todo:
        return fits, flags, model, ()
    for _ in range(_JOINT_ITERATIONS):
        new = list(fits)
        for i in todo:
            new[i], used[i] = refit_with_prior(profiles[i], float(periods[i]), first[i], model, noises[i])
        change = max(abs(new[i].modulation - fits[i].modulation) for i in todo)
        fits = new
        if change < 1e-7:
            break
        model = fit_mtf_model(fits, periods, c_large) or model
    for i in todo:
        p = float(periods[i])
        flags = [f for f in flags if not (f.startswith(f"group {i}: ") and ("alias" in f or "zero crossings" in f))]
        txt = ", ".join(f"M({k / p:.3f}) = {m:.3f} +- {sm:.3f}" for k, (m, sm) in used[i].items())
        flags.append(
            f"group {i}: harmonic(s) {list(used[i])} of the {p:g} px period alias onto others or are sampled near "
            f"their zero crossings; constrained by the MTF fitted to the target's groups ({txt}), uncertainty "
            "included"
        )
    return fits, flags, model, tuple(todo)


#: Most rounds of (joint model, group refits); the aliased terms are a few % of the fundamentals, so a
#: handful reaches the fixed point.
_JOINT_ITERATIONS = 8


def _joint_candidate(fit: GroupFit, period: float, n_samples: int) -> bool:
    """A group whose CTF needs harmonics it cannot observe, and whose phase is identifiable (fundamental not
    within 0.02 cy/px of 0.5 cy/px)."""
    g1 = abs(1 / period - round(1 / period))
    held = bool(held_harmonics(fit.harmonics, period, n_samples))
    return 0.5 - g1 >= 0.02 and fit.cov is not None and (bool(prior_harmonics(fit, period)) or held)


def _mtf_with_std(f, ctf, ctf_std):
    """Inverse Coltman series and its 1-sigma (the series is linear in the CTF samples; groups independent)."""
    mtf = mtf_from_ctf_samples(f, ctf)
    gain = np.array([mtf_from_ctf_samples(f, np.eye(f.size)[j]) for j in range(f.size)])  # [group j, f]
    std = np.sqrt(np.nansum((gain * np.nan_to_num(ctf_std)[:, None]) ** 2, axis=0))
    return mtf, np.where(np.isfinite(ctf_std).all(), std, np.nan)
