"""Platform-motion transfer functions: linear smear and Gaussian jitter.

Frequencies are focal-plane cycles/mm; lengths are focal-plane metres (the budget converts the
system's pixel units with the pitch).
"""

from __future__ import annotations

import numpy as np

from satchain._validate import check_range
from satchain.units import MM_PER_M

__all__ = ["jitter_otf", "smear_otf"]


def smear_otf(fx_cy_per_mm, fy_cy_per_mm, *, smear_alt_m: float, smear_act_m: float = 0.0) -> np.ndarray:
    """OTF of uniform linear motion during the exposure (the paper's eq. 3), centred on mid-exposure.

    ``OTF = sinc(L_y f_y) sinc(L_x f_x)``: the image is averaged over a segment of length ``L_y``
    along-track (``smear_alt_m``) and ``L_x`` across-track (``smear_act_m``). Centring the segment on
    the exposure mid-time makes the OTF real (no shift); it changes sign past ``1 / L``.

    Examples
    --------
    >>> float(smear_otf(0.0, 85.034, smear_alt_m=5.88e-6).round(4))  # one-pixel smear at Nyquist
    0.6366
    """
    ly_mm = check_range("smear_alt_m", smear_alt_m, 0, None) * MM_PER_M
    lx_mm = check_range("smear_act_m", smear_act_m, 0, None) * MM_PER_M
    fx, fy = _outer(*np.broadcast_arrays(np.asarray(fx_cy_per_mm, float), np.asarray(fy_cy_per_mm, float)))
    return np.sinc(ly_mm * fy) * np.sinc(lx_mm * fx)


def jitter_otf(fx_cy_per_mm, fy_cy_per_mm, *, rms_x_m: float, rms_y_m: float) -> np.ndarray:
    """OTF of random high-frequency line-of-sight jitter with Gaussian statistics.

    ``OTF = exp(-2 pi^2 (sigma_x^2 f_x^2 + sigma_y^2 f_y^2))`` (Fiete, *Modeling the Imaging Chain of
    Digital Cameras*, 2010, sec. 8.4; Holst 2011).

    Examples
    --------
    >>> round(float(jitter_otf(0.0, 85.034, rms_x_m=0.0, rms_y_m=5.88e-6)), 4)  # 1 px rms at Nyquist
    0.0072
    """
    sx = check_range("rms_x_m", rms_x_m, 0, None) * MM_PER_M
    sy = check_range("rms_y_m", rms_y_m, 0, None) * MM_PER_M
    fx, fy = _outer(*np.broadcast_arrays(np.asarray(fx_cy_per_mm, float), np.asarray(fy_cy_per_mm, float)))
    return np.exp(-2.0 * np.pi**2 * ((sx * fx) ** 2 + (sy * fy) ** 2))


def _outer(fx: np.ndarray, fy: np.ndarray):
    """On an outer grid (``fx`` varying along the last axis only and ``fy`` along the first only, as broadcast
    views give them), their one distinct row and column, which broadcast back to the grid in the arithmetic
    that follows: each factor computed once per row or column, the same floats; else the grids as given."""
    if fx.ndim == 2 and fx.strides[0] == 0 and fy.strides[1] == 0:
        return fx[:1], fy[:, :1]
    return fx, fy
