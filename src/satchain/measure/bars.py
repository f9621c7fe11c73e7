"""Bar-target CTF and the MTF derived from it by the inverse Coltman series.

Each bar group is a square wave of known period (``periods_px``, one bright + one dark bar).  Its profile
across the bars is averaged along the bars; the contrast transfer is ``(max - min) / (max + min)`` of that
profile, divided by the large-area contrast of the target (``(bright - dark) / (bright + dark)`` of large
uniform areas).  The MTF at the group frequencies follows from Coltman (1954)'s inverse series, applied
here to the measured, discrete CTF (linear interpolation between groups, zero above the highest measured
frequency; so the groups should reach the frequency where the CTF vanishes).  ``satchain.ctf`` has the same
series for continuous CTF functions; this module keeps its own so measurement stays independent of prediction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._validate import check_choice, check_positive
from satchain.errors import InputError
from satchain.measure._common import ResultMixin, crop_roi
from satchain.units import cy_per_px_to_cy_per_m_ground

__all__ = ["BarsResult", "measure_bars", "coltman_inverse_coefficients", "mtf_from_ctf_samples"]


@dataclass(frozen=True)
class BarsResult(ResultMixin):
    """CTF per bar group and the MTF from the inverse Coltman series, at ``f_cy_per_px = 1 / period``."""

    f_cy_per_px: np.ndarray
    periods_px: np.ndarray
    ctf: np.ndarray
    mtf: np.ndarray
    large_area_contrast: float
    direction: str
    f_cy_per_m_ground: np.ndarray | None = None


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
    >>> np.round(mtf_from_ctf_samples(f, 4 / np.pi * np.array([0.5, 0.0])), 3)
    array([0.5, 0. ])
    """
    f = np.asarray(f_cy_per_px, dtype=float)
    c = np.asarray(ctf, dtype=float)
    order = np.argsort(f)
    fs, cs = f[order], c[order]
    out = np.zeros_like(f)
    for k, b in coltman_inverse_coefficients(n_terms):
        out += b * np.interp(k * f, fs, cs, right=0.0)
    return np.pi / 4 * out


def measure_bars(
    image,
    *,
    periods_px,
    group_rois,
    direction: str = "ACT",
    levels=None,
    pixel_m: float | None = None,
) -> BarsResult:
    """CTF of bar groups and the MTF from the inverse Coltman series.

    Parameters
    ----------
    image : array_like, 2-D
    periods_px : sequence of float
        Period (bright + dark bar) of each group, px.
    group_rois : sequence of (x0, y0, x1, y1)
        One region per group, covering whole bars.
    direction : {"ACT", "ALT"}
        ``ACT``: bars parallel to y, profile along x (the ACT CTF); ``ALT``: bars parallel to x.
    levels : (dark, bright), optional
        Large-area dark and bright levels; by default the 2nd and 98th percentiles of the lowest-frequency
        group.
    pixel_m : float, optional
        Ground sample distance; adds ``f_cy_per_m_ground``.

    Examples
    --------
    >>> x = np.arange(64)
    >>> img = np.tile(np.where((x // 4) % 2 == 0, 200.0, 50.0), (20, 1))
    >>> r = measure_bars(img, periods_px=[8.0], group_rois=[(0, 0, 64, 20)], levels=(50.0, 200.0))
    >>> float(r.ctf[0])
    1.0
    """
    check_choice("direction", direction, ("ACT", "ALT"))
    periods = np.array([check_positive("periods_px", p) for p in periods_px], dtype=float)
    if len(group_rois) != periods.size or periods.size == 0:
        raise InputError(f"group_rois: {len(group_rois)} regions for {periods.size} periods; need one per group")
    profiles = []
    for roi in group_rois:
        data = crop_roi(image, roi, min_size=2)
        profiles.append(data.mean(axis=0) if direction == "ACT" else data.mean(axis=1))
    for p, prof in zip(periods, profiles, strict=True):
        if prof.size < p:
            raise InputError(f"group_rois: a region of {prof.size} px across the bars is shorter than its period {p:g}")
    if levels is None:
        dark, bright = np.percentile(profiles[int(np.argmax(periods))], [2, 98])
    else:
        dark, bright = (float(v) for v in levels)
    if not (bright > dark and bright + dark > 0):
        raise InputError(f"levels = ({dark:g}, {bright:g}): need bright > dark and a positive mean")
    c_large = (bright - dark) / (bright + dark)
    ctf = np.array([(p.max() - p.min()) / (p.max() + p.min()) for p in profiles]) / c_large
    f = 1.0 / periods
    return BarsResult(
        f_cy_per_px=f,
        periods_px=periods,
        ctf=ctf,
        mtf=mtf_from_ctf_samples(f, ctf),
        large_area_contrast=float(c_large),
        direction=direction,
        f_cy_per_m_ground=None if pixel_m is None else cy_per_px_to_cy_per_m_ground(f, gsd_m=pixel_m),
    )
