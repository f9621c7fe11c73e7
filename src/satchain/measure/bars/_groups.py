"""The per-group stage of :func:`satchain.measure.bars.measure_bars`: each group's profile, fit and checks, and
the refusal of a group alone (issue 18: a target was refused whole because one 2 px group was unusable).

In a target of two or more groups a group that is not bars at its period (too short, another period dominating,
a profile no periodic model fits and the target's MTF model does not render) is refused alone, with its reason;
the others are measured.  A lone group is refused as before.

A group whose modulation does not stand :data:`SIGNIFICANT_SIGMAS` above the noise, in a target of two or more
groups, is measured at the noise floor (issue 29): flagged ``at_noise_floor``, its CTF ~0 with its 1-sigma is a
result (a blur whose MTF vanishes at its frequency, as a smear's sinc null), kept out of the joint MTF model and
not corrected; refused only when another period stands out in its region or its profile is not noise about a
level, and the call is refused when no group of the target stands above the noise (no bars are seen).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

import numpy as np

from satchain.errors import InputError
from satchain.measure._common import clipping_flag, crop_roi
from satchain.measure._keys import AT_NOISE_FLOOR
from satchain.measure.bars._finite import group_centres
from satchain.measure.bars._fit import GroupFit, fit_group

__all__ = ["AT_NOISE_FLOOR", "measure_groups", "validate_deferred", "scatter", "renumber", "refusal_flags", "Groups"]


def _profile(image, roi, direction: str, period: float, index: int, full_scale: float | None = None):
    """Profile across the bars (mean along them), its noise (from the rows' scatter about it) and flags
    (clipping only on evidence: pixels at ``full_scale``, or a flat run at an extreme that shows saturation)."""
    data = crop_roi(image, roi, min_size=2)
    work = data if direction == "ACT" else data.T  # rows run along the bars' profile
    prof = work.mean(axis=0)
    if prof.size < 1.5 * period or prof.size < 4:
        raise InputError(
            f"group_rois[{index}] = {tuple(roi)!r}: {prof.size} px across the bars covers "
            f"{prof.size / period:.2f} periods of {period:g} px; need at least 1.5 (two bars) and 4 px"
        )
    rows = work.shape[0]
    noise = None
    if rows >= 2:
        noise = float(np.std(work - prof[None, :], ddof=0) * np.sqrt(rows / (rows - 1)) / np.sqrt(rows))
    clip = clipping_flag(work, full_scale=full_scale, noise_std=None if noise is None else noise * np.sqrt(rows))
    return prof, noise, ([f"group {index}: {clip}"] if clip else [])


#: A fitted modulation is significant above this many of its 1-sigma.
SIGNIFICANT_SIGMAS = 5.0


def _check_group(fit: GroupFit, prof: np.ndarray, period: float, index: int, deferred: dict | None = None,
                 floor_ok: bool = False, noise: float | None = None) -> list[str]:  # fmt: skip
    """Refuse profiles that are not bars at ``period``; return flags.  With ``deferred`` (a target of three or
    more groups), a profile the periodic model misfits is not refused here: its refusal is recorded under
    ``index`` and decided against the target's MTF model (``validate_deferred``).  With ``floor_ok`` (a target
    of two or more groups), a modulation not above the noise is a measurement at the noise floor
    (:func:`_noise_floor_flag`; ``noise``: the profile's, from its rows), not a refusal."""
    from satchain.measure.bars._fit import period_gain

    g_claim, g_other, f_other = period_gain(prof, period)
    if floor_ok and not _significant(fit):
        return _noise_floor_flag(fit, prof, period, index, (g_other, f_other), noise)
    if prof.size >= 2.5 * period and not g_claim > g_other:  # shorter: too few bins (misfit check below)
        raise InputError(
            f"periods_px[{index}] = {period:g}: the profile's dominant period is {1 / f_other:.3g} px "
            f"(frequency {f_other:.3f} cy/px), not {period:g} px: no bars at that period in the region"
        )
    amp = abs(float(np.sum(fit.amps)))
    if not _significant(fit):
        raise InputError(
            f"group_rois[{index}]: no significant bar modulation at period {period:g} px "
            f"({fit.modulation:.3g} +- {fit.modulation_std:.2g})"
        )
    flags = []
    if fit.misfit > 0.25 * amp:
        on_hump = _misfit_on_hump(prof, period, fit)
        if not on_hump <= 0.25 * amp:
            ratio = f"{fit.misfit / amp:.0%}" if fit.misfit < 100 * amp else f"{fit.misfit / amp:.1e} x"
            msg = (
                f"group_rois[{index}]: the profile is not a bar pattern of period {period:g} px (rms misfit "
                f"{fit.misfit:.3g} = {ratio} of the bar amplitude {amp:.3g}, also with a smooth envelope: a "
                "single bar or edge, bars too blurred for the few samples in the region, or samples on the bars' "
                "edges)"
            )
            if deferred is None:
                raise InputError(msg)
            deferred[index] = msg
            return []
        flags.append(
            f"group {index}: the bars sit on a hump ({fit.misfit / amp:.0%} of the bar amplitude, "
            f"{on_hump / amp:.0%} once a smooth envelope is allowed): a short group under a wide blur; the CTF of "
            "a lone group is then biased (a target's joint correction removes it)"
        )
    last = abs(float(fit.amps[-1])) / abs(float(np.sum(fit.amps)))
    if len(fit.harmonics) == 1:
        flags.append(
            f"group {index}: only the fundamental is separable at {period:g} px; harmonics 3+ alias onto it: a "
            "sharp system's CTF may be off by a few %"
        )
    elif last > 0.02:
        flags.append(
            f"group {index}: harmonics {fit.harmonics[-1] + 2}+ of the {period:g} px period alias onto fitted ones "
            f"and are not fitted (last fitted harmonic {fit.harmonics[-1]}: {last:.0%} of the modulation): the "
            "CTF may be off by a few % for a sharp system"
        )
    if fit.unobserved:
        flags.append(
            f"group {index}: harmonic(s) {list(fit.unobserved)} of the {period:g} px period alias to 0.5 cy/px and "
            "are sampled at their zero crossings at this phase (unobserved, not in the CTF): a sharp system's CTF "
            "may be off by a few %"
        )
    if period < 2.5:
        flags.append(_short_period_flag(index, period))
    return flags


def _significant(fit: GroupFit) -> bool:
    """The fitted modulation stands above :data:`SIGNIFICANT_SIGMAS` of its 1-sigma."""
    amp = abs(float(np.sum(fit.amps)))
    above = np.isfinite(fit.modulation_std) and fit.modulation > SIGNIFICANT_SIGMAS * fit.modulation_std
    return bool(above and amp > 0)


def _noise_floor_flag(fit: GroupFit, prof: np.ndarray, period: float, index: int, other: tuple[float, float],
                      noise: float | None) -> list[str]:  # fmt: skip
    """A group whose modulation is not above the noise: measured at the noise floor (its CTF ~0 with its
    1-sigma: a blur whose MTF vanishes at the group's frequency, e.g. a smear's sinc null, is a result), unless
    another period stands significantly in its region, or the profile is not noise about a level (its fit's
    misfit above the rows' noise): then no bars of this period are there (refused)."""
    n, (g_other, f_other) = prof.size, other
    noise = fit.noise if noise is None or not np.isfinite(noise) else float(noise)
    other_amp, amp_sigma = np.sqrt(2.0 * max(g_other, 0.0) / n), noise * np.sqrt(2.0 / n)
    if n >= 2.5 * period and other_amp > SIGNIFICANT_SIGMAS * amp_sigma:
        raise InputError(
            f"periods_px[{index}] = {period:g}: no modulation above the noise at {period:g} px, but a period of "
            f"{1 / f_other:.3g} px stands out (frequency {f_other:.3f} cy/px): no bars at that period in the region"
        )
    if fit.misfit > 3 * max(noise, 1e-12):
        raise InputError(
            f"group_rois[{index}]: no modulation above the noise at period {period:g} px, and the profile is not "
            f"noise about a level either (rms misfit {fit.misfit:.3g} > 3 x the rows' noise {noise:.2g}): no bars "
            "of that period in the region"
        )
    flags = [
        f"group {index}: {AT_NOISE_FLOOR}: modulation {fit.modulation:.3g} +- {fit.modulation_std:.2g} is not above "
        f"{SIGNIFICANT_SIGMAS:g} sigma of the noise: the CTF is ~0 (measured at the noise floor, with its 1-sigma), "
        "not corrected to the square-wave CTF"
    ]
    if period < 2.5:
        flags.append(_short_period_flag(index, period))
    return flags


def _short_period_flag(index: int, period: float) -> str:
    return (
        f"group {index}: period {period:g} px < 2.5 px: the CTF depends on the sampling phase "
        "(near 2 px: the sampled modulation, a lower bound)"
    )


def _misfit_on_hump(prof: np.ndarray, period: float, fit: GroupFit) -> float:
    """Rms misfit (less the noise) of the group's harmonics at its phase plus a smooth quadratic envelope: a
    finite group under a blur wider than its bars sits on a hump the periodic model alone cannot follow."""
    y = np.asarray(prof, dtype=float)
    x = np.arange(y.size, dtype=float)
    u = (x - x.mean()) / max(y.size, 1)
    ph = 2 * np.pi * np.outer(x - fit.x0, np.asarray(fit.harmonics, dtype=float)) / period
    d = np.column_stack([np.ones_like(x), u, u * u, np.cos(ph)])
    dof = y.size - d.shape[1]
    if dof < 1:
        return np.inf
    resid = y - d @ np.linalg.lstsq(d, y, rcond=None)[0]
    s2 = float(np.sum(resid**2)) / dof - (fit.noise if np.isfinite(fit.noise) else 0.0) ** 2
    return float(np.sqrt(max(s2, 0.0)))


def validate_deferred(deferred, model, fits, profiles, periods, c_large, n_bars, flags):
    """A group the periodic model misfit (a short group on the hump of a wide blur) is kept only when the
    target's MTF model, rendering the whole group as it lies in its region, reproduces its profile (rms
    misfit, after a gain and an offset, within 25 % of the bar amplitude); otherwise it is refused with the
    original reason.  Returns the flags and ``{index: reason}`` of the refused."""
    refused = {}
    for i, msg in deferred.items():
        p, prof = float(periods[i]), np.asarray(profiles[i], dtype=float)
        centres = None
        if model is not None and n_bars is not None:
            centres, _ = group_centres(fits[i].x0, p, prof.size, int(n_bars))
        if centres is None:
            refused[i] = msg
            continue
        synth = model.render_group(p, centres, prof.size, c_large)
        d = np.column_stack([synth, np.ones_like(synth)])
        coef = np.linalg.lstsq(d, prof, rcond=None)[0]
        resid = prof - d @ coef
        s2 = (
            float(np.sum(resid**2)) / max(prof.size - 2, 1)
            - (fits[i].noise if np.isfinite(fits[i].noise) else 0.0) ** 2
        )
        amp = abs(float(np.sum(fits[i].amps)))
        misfit = float(np.sqrt(max(s2, 0.0)))
        if not (coef[0] > 0 and misfit <= 0.25 * amp):
            refused[i] = msg
            continue
        flags.append(
            f"group {i}: the bars sit on the hump of a short group under a wide blur ({fits[i].misfit / amp:.0%} "
            f"misfit for a periodic profile); the target's MTF model renders the group within {misfit / amp:.0%}: "
            "measured, with the square-wave correction"
        )
        if periods[i] < 2.5:  # kept on the model: its sampling caveat holds as for any measured group
            flags.append(_short_period_flag(i, float(periods[i])))
    return flags, refused


@dataclass
class Groups:
    """Per group (all of them): profile, fit, noise, flags; ``refused`` maps an index to its reason; ``floor``:
    the groups measured at the noise floor."""

    profiles: dict = field(default_factory=dict)
    fits: dict = field(default_factory=dict)
    noises: dict = field(default_factory=dict)
    flags: dict = field(default_factory=dict)
    deferred: dict = field(default_factory=dict)
    refused: dict = field(default_factory=dict)
    floor: set = field(default_factory=set)  # measured at the noise floor (AT_NOISE_FLOOR)


def measure_groups(image, periods, group_rois, direction, full_scale: float | None = None) -> Groups:
    """Profile, fit and check every group.  In a target of two or more groups, a group that is not bars at its
    period (or too short, or without a significant modulation) is refused alone (its reason kept) and the others
    measured; the call is refused when none is left, or for a lone group."""
    g = Groups()
    deferred: dict[int, str] | None = {} if periods.size >= 3 else None
    for i, (p, roi) in enumerate(zip(periods, group_rois, strict=True)):
        fl = []
        try:
            prof, noise, fl = _profile(image, roi, direction, p, i, full_scale)
            fit = fit_group(prof, p, noise)
            fl = fl + _check_group(fit, prof, p, i, deferred, floor_ok=periods.size >= 2, noise=noise)
        except InputError as exc:
            why = str(exc) + "".join(f" ({f.removeprefix(f'group {i}: ')})" for f in fl)  # e.g. the clipping
            if periods.size < 2:
                raise InputError(why) from None
            g.refused[i] = why
            continue
        if deferred is not None and i in deferred:  # kept out of the joint model until the model has explained it
            fit = replace(fit, cov=None)
            g.deferred[i] = deferred.pop(i)
        if any(f.startswith(f"group {i}: {AT_NOISE_FLOOR}") for f in fl):  # out of the joint model, uncorrected
            fit = replace(fit, cov=None)
            g.floor.add(i)
        g.profiles[i], g.fits[i], g.noises[i], g.flags[i] = prof, fit, noise, fl
    if len(g.refused) == periods.size:
        reasons = "; ".join(f"group {i}: {m}" for i, m in sorted(g.refused.items()))
        raise InputError(f"group_rois: no group is measurable ({reasons})")
    if len(g.refused) + len(g.floor) == periods.size:  # no bars seen anywhere: no target to measure
        reasons = "; ".join(f"group {i}: {m}" for i, m in sorted(g.refused.items()))
        raise InputError(
            f"group_rois: no group is measurable: no group's modulation stands above the noise (groups "
            f"{sorted(g.floor)}), so no bar target is seen in the regions" + (f"; {reasons}" if reasons else "")
        )
    return g


def scatter(values, kept, n: int) -> np.ndarray:
    """Per-kept-group values placed at their indices among ``n`` groups (NaN elsewhere)."""
    out = np.full(n, np.nan)
    out[np.asarray(kept, dtype=int)] = np.asarray(values, dtype=float)
    return out


def renumber(flags, kept) -> list[str]:
    """Flags of the kept groups (numbered 0..k-1 by the target's core) renumbered to the caller's indices."""
    out = []
    for f in flags:
        m = re.match(r"group (\d+): ", f)
        out.append(f"group {kept[int(m.group(1))]}: {f[m.end() :]}" if m else f)
    return out


def refusal_flags(refused: dict) -> list[str]:
    return [f"group {i}: refused (the other groups are measured): {msg}" for i, msg in sorted(refused.items())]
