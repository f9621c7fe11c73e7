"""The 1-sigma of the errors that :mod:`satchain.comparison` checks, where a measurement does not report
one directly: the slanted edge's angle, an edge's RER and the GIQE 5 NIIRS measured from the edges and the
image SNR (with the SNR's measured sigma). Pure functions of numbers and lists; the prediction is exact
for the simulated model, so every sigma here is the measurement's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["SNR_REL_SIGMA", "edge_angle_sigma", "edge_angle_sigma_deg", "niirs_sigma", "rer_sigma_bound"]

#: Fallback relative 1-sigma of the measured contrast SNR, used only when the measurement gives no
#: ``snr_sigma`` of its own (:func:`satchain.measure.snr.measure_snr` measures one by a bootstrap unless it
#: has fewer than 8 background patches; an SNR from elsewhere may carry none): the sampling error of the
#: noise sigma from one 16 x 16 px background patch (~240 pixel differences: ~1 / sqrt(2 * 240) ~ 0.05).
#: The NIIRS row then says it used it.
SNR_REL_SIGMA = 0.05


def _finite(v) -> float | None:
    if v is None or isinstance(v, bool):
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def edge_angle_sigma_deg(*, cnr: float, n_lines: int, width_px: int, angle_deg: float) -> float:
    """1-sigma (deg) of a slanted edge's measured angle, from the noise of its per-line edge positions.

    measure_edge locates the edge on each line as the centroid of the central-difference derivative within
    ``h = max(4, min(12, width_px // 6))`` px of the fitted line, then fits a straight line to the ``n``
    positions. With white pixel noise of 1 / ``cnr`` of the step, a centroid's 1-sigma is
    ``sqrt(sum c_j^2) / cnr`` px, where ``c_j`` are the weights the centroid gives each pixel's noise
    (-1 inside the window, ``h / 2`` and ``(h - 1) / 2`` at its two ends on each side:
    ``sum c_j^2 = 2h - 1 + (h^2 + (h - 1)^2) / 2``); the least-squares slope of ``n`` unit-spaced positions
    then has ``sigma_c sqrt(12 / (n (n^2 - 1)))``, and the angle ``sigma_slope cos^2(angle)`` rad. Sub-pixel
    bias of a centroid and noise correlated between lines are not included (an estimate, not a bound; within
    10 % of the scatter of noisy rendered edges, tests/measure/test_edge_angle_sigma.py).

    Examples
    --------
    >>> round(edge_angle_sigma_deg(cnr=100.0, n_lines=100, width_px=60, angle_deg=5.0), 4)
    0.0206
    """
    h = max(4, min(12, int(width_px) // 6))
    s_c = math.sqrt(2 * h - 1 + (h * h + (h - 1) ** 2) / 2) / cnr
    n = int(n_lines)
    s_slope = s_c * math.sqrt(12.0 / (n * (n * n - 1)))
    return math.degrees(s_slope * math.cos(math.radians(angle_deg)) ** 2)


def edge_angle_sigma(e: Mapping[str, Any]) -> float | None:
    """The angle 1-sigma (deg) of a measured edge entry: its own (``angle_deg_sigma``) when it reports one,
    else :func:`edge_angle_sigma_deg` from its ``cnr``, ``n_lines``, ``roi_px`` and image angle (None
    without them)."""
    own = _finite(e.get("angle_deg_sigma", e.get("angle_deg_std")))
    if own is not None:
        return own
    cnr, n, roi, a = _finite(e.get("cnr")), e.get("n_lines"), e.get("roi_px"), _finite(e.get("edge_angle_deg_image"))
    if cnr is None or cnr <= 0 or not n or n < 3 or not roi or a is None:
        return None
    act = str(e.get("direction")).upper() == "ACT"
    width = roi[2] - roi[0] if act else roi[3] - roi[1]
    return edge_angle_sigma_deg(cnr=cnr, n_lines=int(n), width_px=int(width), angle_deg=a if act else 90.0 - a)


def rer_sigma_bound(f_cy_per_px: Sequence[float] | None, mtf_sigma: Sequence[float | None] | None) -> float | None:
    """A bound on the 1-sigma of an edge's RER from its MTF's per-frequency 1-sigma.

    RER = ESF(0.5) - ESF(-0.5) = 2 int_0^inf MTF(f) sinc(f) df (f in cy/px, a symmetric LSF), so its
    1-sigma is at most ``2 int |sinc(f)| sigma_MTF(f) df`` (the noise of all frequencies fully correlated:
    an upper bound whatever their correlation), over the measured band. None without two finite sigmas.

    Examples
    --------
    >>> round(rer_sigma_bound([0.0, 0.5, 1.0], [0.01, 0.01, 0.01]), 4)  # 2 * 0.01 * (trapezoid of |sinc|)
    0.0114
    """
    if not mtf_sigma or not f_cy_per_px or len(mtf_sigma) != len(f_cy_per_px):
        return None
    f = np.asarray(f_cy_per_px, float)
    sd = np.array([np.nan if v is None else v for v in mtf_sigma], float)
    ok = np.isfinite(sd)
    if ok.sum() < 2:
        return None
    return float(2 * np.trapezoid(np.abs(np.sinc(f[ok])) * sd[ok], f[ok]))


def niirs_sigma(rer_act: float, rer_alt: float, snr: float, *, rer_act_sigma: float, rer_alt_sigma: float,
                gsd_in: float, elevation_deg: float, snr_sigma: float | None = None) -> float:  # fmt: skip
    """1-sigma of a GIQE 5 NIIRS measured from per-axis RERs and a contrast SNR: their sigmas (the SNR's
    ``snr_sigma``, measured; :data:`SNR_REL_SIGMA` of it when None) through GIQE 5 (with
    :func:`satchain.prediction.quality.giqe5_rer`) by central differences, in quadrature (independent errors)."""
    from satchain.prediction.quality import giqe5, giqe5_rer

    def niirs(a: float, b: float, s: float) -> float:
        return giqe5(gsd_in=gsd_in, rer=giqe5_rer(a, b), snr=s, elevation_deg=elevation_deg)

    x = np.array([rer_act, rer_alt, snr], float)
    sx = np.array([rer_act_sigma, rer_alt_sigma, SNR_REL_SIGMA * snr if snr_sigma is None else snr_sigma])
    var = 0.0
    for k in range(3):
        h = np.zeros(3)
        h[k] = 1e-4 * x[k]
        var += ((niirs(*(x + h)) - niirs(*(x - h))) / (2 * h[k]) * sx[k]) ** 2
    return float(math.sqrt(var))
