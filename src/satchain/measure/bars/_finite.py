"""From a measured bar group to Coltman's square-wave CTF (see :mod:`satchain.measure.bars`).

Coltman's CTF, the quantity the inverse series turns into an MTF and the one a prediction gives, is the
modulation of an *infinite* square wave.  A bar group is finite (3 bars in the paper's targets), sampled at one
grid phase, and its fit cannot see every harmonic.  Each of these moves what one group measures away from the
square-wave CTF:

- the finite group: a long-tailed PSF (diffraction: the line spread falls as 1 / x^2) lifts the troughs of an
  infinite grating more than a 3-bar group's, and a wide blur puts the group on a hump; the central bar of a
  3-bar group is 0.010-0.018 above Coltman's CTF for an annular aperture at Q 1-1.5, 0.002 for a Gaussian;
- the harmonics aliased onto fitted ones or sampled at their zero crossings (``_barjoint``), and the grid
  phase.

With the target's joint MTF model ``M`` (``_barjoint``), each group is rendered exactly as it lies in its region
(same bar centres, same samples, the large-area contrast) through ``M``, and measured by the same estimator;
the difference between ``M``'s Coltman CTF and that estimate is the estimator's bias for this group at this
phase, and is added to the measured CTF.  What is left is the difference of that bias between the true MTF and
the model: second order.  Its 1-sigma is half the change of the correction between the model moved by -1 and
+1 sigma (``MtfModel.log_sigma``), and goes into the CTF's 1-sigma.

The group's geometry comes from the region's convention (first to last bar centre, as ``measure auto`` and the
CLI make it) and the fitted phase; where they disagree by more than half a pixel the region is not one whole
group of ``n_bars``, the correction is not applied and a flag says so.
"""

from __future__ import annotations

import numpy as np

from satchain.measure.bars._fit import GroupFit, fit_group, plateau
from satchain.measure.bars._joint import MtfModel, refit_with_prior

__all__ = ["finite_group_correction", "group_centres"]

#: Largest misplacement (px) of the first / last bar centre from the region's ends accepted as one group.
CENTRE_TOL = 0.5
#: Corrections above this are listed in the flags (smaller ones are routine: ``BarsResult.ctf_correction``).
FLAG_CORRECTION = 0.01


def group_centres(x0: float, period: float, length: int, n_bars: int) -> tuple[np.ndarray | None, float]:
    """Bright-bar centres (px in the region) of an ``n_bars`` group whose first and last centres are the
    region's ends (first in (-1, 0], last in [L - 1, L)), given a fitted centre ``x0`` (mod ``period``); None
    and the misplacement (px) when they do not fit."""
    best, first = np.inf, 0.0
    for cand in (x0 % period - period, x0 % period, x0 % period - 2 * period):
        last = cand + (n_bars - 1) * period
        miss = max(cand - 0.0, -1.0 - cand, 0.0) + max(length - 1.0 - last, last - length, 0.0)
        if miss < best:
            best, first = miss, cand
    if best > CENTRE_TOL:
        return None, best
    return first + period * np.arange(n_bars), best


def _estimate(prof, period, model, joint: bool, use_plateau: bool, noise=None) -> float:
    """The measurement's own estimator (fit, the joint refit if the group had it, the plateau if used)."""
    fit: GroupFit = fit_group(prof, period, noise)
    if joint:
        fit, _ = refit_with_prior(prof, period, fit, model, noise)
    if use_plateau:
        found, _ = plateau(prof, fit, period, force=True)
        if found is not None:
            return float(found[0])
    return float(fit.modulation)


def finite_group_correction(
    model: MtfModel, fits, profiles, periods, c_large: float, n_bars: int, joint, plateau_used, flags
):
    """Per group: the correction to add to the measured CTF, its 1-sigma, and the flags (see the module)."""
    n = len(fits)
    corr, std = np.zeros(n), np.zeros(n)
    flags = list(flags)
    for i in range(n):
        p, length = float(periods[i]), int(np.asarray(profiles[i]).size)
        g1 = abs(1 / p - round(1 / p))
        if 0.5 - g1 < 0.02:  # phase not identifiable at the Nyquist frequency: nothing to render it at
            continue
        centres, miss = group_centres(fits[i].x0, p, length, n_bars)
        if centres is None:
            flags.append(
                f"group {i}: its region does not run from the first to the last bar centre of a {n_bars}-bar group "
                f"(off by {miss:.2f} px): the CTF is that of the bars in the region, not corrected to the "
                "square-wave CTF"
            )
            continue
        vals = {}
        for shift in (0.0, -1.0, 1.0):
            synth = model.render_group(p, centres, length, c_large, shift)
            est = _estimate(synth, p, model, i in joint, bool(plateau_used[i]))
            vals[shift] = model.ctf(p, shift) - est / c_large
        corr[i] = vals[0.0]
        std[i] = 0.5 * abs(vals[1.0] - vals[-1.0])
        if abs(corr[i]) > FLAG_CORRECTION:
            flags.append(
                f"group {i}: CTF corrected by {corr[i]:+.3f} +- {std[i]:.3f} to the square-wave (Coltman) CTF (finite "
                f"{n_bars}-bar group, aliased harmonics, grid phase), through the MTF fitted to the target's groups"
            )
    return corr, std, flags
