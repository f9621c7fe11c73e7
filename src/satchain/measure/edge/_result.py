"""The fields of a slanted-edge result (:class:`satchain.measure.edge.EdgeResult`) from the measured curves.

The MTF's values at Nyquist and MTF50, the GIQE edge metrics (RER, overshoot) of the normalised ESF, the edge's
angle and a point on it in image coordinates, and the output scales (ground, focal plane).
"""

from __future__ import annotations

import numpy as np

from satchain.measure._common import first_crossing
from satchain.measure.edge._locate import curvature
from satchain.units import cy_per_px_to_cy_per_m_ground, cy_per_px_to_cy_per_mm

__all__ = ["NU_STEP", "I_NYQ", "result_fields", "edge_point", "angle_deg", "edge_metrics"]

NU_STEP = 0.005  # the output frequencies' step (cy/px)
I_NYQ = int(round(0.5 / NU_STEP))  # index of Nyquist on the output frequencies


def result_fields(curve, esf, fit, stats, scales, lines, imaged) -> dict:
    """The fields of the :class:`~satchain.measure.edge.EdgeResult` (keyword arguments): ``curve = (f, mtf,
    sigma, axis, scale)``, ``esf = (x, esf)``, ``fit = (coef, rows, slope, transposed, roi)``, ``stats =
    (contrast, noise, window, bin width, gradient, direction, flags)``, ``scales = (pixel_m, pitch_m)``, ``lines
    = (lines, edge positions, their 1-sigma)`` and ``imaged = (MTF aligned, MTF as imaged, its 1-sigma, los
    motion px rms)``."""
    f, mtf, mtf_sig, axis, scale = curve
    x, esf_n = esf
    coef, rows, slope, transposed, roi = fit
    contrast, sigma, half_w, w, grad, direction, flags = stats
    pixel_m, pitch_m = scales
    rer, overshoot = edge_metrics(x, esf_n)
    return dict(
        f_cy_per_px=f,
        mtf=mtf,
        esf_x_px=x,
        esf=esf_n,
        lsf=np.gradient(esf_n, x),
        angle_deg=angle_deg(slope, transposed),
        direction=direction,
        mtf_at_nyquist=float(mtf[I_NYQ]),
        mtf50_cy_per_px=first_crossing(f, mtf, 0.5),
        rer=rer,
        overshoot=overshoot,
        contrast=float(contrast),
        noise_sigma=float(sigma),
        window_half_width_px=float(half_w),
        n_lines=len(rows),
        warnings=tuple(t for _, t in flags),
        f_cy_per_m_ground=None if pixel_m is None else cy_per_px_to_cy_per_m_ground(f, gsd_m=pixel_m),
        f_cy_per_mm=None if pitch_m is None else cy_per_px_to_cy_per_mm(f, pitch_m=pitch_m),
        mtf_sigma=mtf_sig,
        mtf_at_nyquist_sigma=float(mtf_sig[I_NYQ]),
        flags=tuple(c for c, _ in flags),
        fit_degree=len(coef) - 1,
        curvature_per_px=curvature(coef, rows),
        cnr=float(abs(contrast) / sigma) if sigma > 0 else float("inf"),
        bin_width_px=float(w),
        illumination_gradient_per_px=float(grad),
        edge_point_xy=edge_point(coef, rows, transposed, roi),
        frequency_axis=axis,
        frequency_scale=float(scale),
        lines=lines[0],
        edge_position_px=lines[1],
        edge_position_sigma_px=lines[2],
        mtf_aligned=imaged[0],
        mtf_as_imaged=imaged[1],
        mtf_as_imaged_sigma=imaged[2],
        mtf_as_imaged_at_nyquist=float(imaged[1][I_NYQ]),
        los_motion_rms_px=float(imaged[3]),
    )


def edge_point(coef, rows, transposed: bool, roi) -> tuple[float, float]:
    """(x, y) in the image of the fitted edge at the middle line used."""
    r = float(np.mean(rows))
    c = float(np.polyval(coef, r))
    x, y = (r, c) if transposed else (c, r)
    if hasattr(roi, "to_roi"):
        roi = roi.to_roi()
    if roi is not None:
        x, y = x + int(roi[0]), y + int(roi[1])
    return (x, y)


def angle_deg(slope: float, transposed: bool) -> float:
    """Angle of the edge line from the image y axis, in (-90, 90]."""
    dx, dy = (1.0, slope) if transposed else (slope, 1.0)
    ang = float(np.degrees(np.arctan2(dx, dy)))
    if ang > 90.0:
        ang -= 180.0
    elif ang <= -90.0:
        ang += 180.0
    return ang


def edge_metrics(x: np.ndarray, esf: np.ndarray):
    """GIQE RER = ESF(+0.5) - ESF(-0.5); overshoot H = max in [1, 3] px if it peaks there, else ESF(1.25)."""
    rer = float(np.interp(0.5, x, esf) - np.interp(-0.5, x, esf))
    xs = np.arange(1.0, 3.0 + 1e-9, 0.25)
    es = np.interp(xs, x, esf)
    i = int(np.argmax(es))
    overshoot = float(es[i]) if i < xs.size - 1 else float(np.interp(1.25, x, esf))
    return rer, overshoot
