"""The hyperbolic-wedge measurer of :func:`satchain.measure.auto.measure_auto`: the paper's contrast scan over the
stripes only (see that module's docstring), a diagonal wedge first resampled onto its own axes."""

from __future__ import annotations

import numpy as np

from satchain.errors import InputError
from satchain.measure._auto_common import AutoContext, AutoItem, Frame, Skip
from satchain.measure._common import to_jsonable
from satchain.measure.wedge import measure_wedge
from satchain.scene.targets import HyperbolicWedge

__all__ = ["wedge_item"]


def _wedge_geometry(it: dict):
    """(w0, x0, length, n_stripes, horizontal, local origin) from a hyperbolic-wedge truth record."""
    w0, x0 = float(it["line_width_start_m"]), float(it["x0_m"])
    horizontal = str(it["orientation"]).lower() == "horizontal"
    return w0, x0, float(it["length_m"]), int(it["n_stripes"]), horizontal, tuple(it["local_origin_m"])


def _diagonal_wedge_grid(refl: np.ndarray, it: dict, frame: Frame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A diagonal wedge resampled onto its own (t, s) axes -- s at the pixel spacing, t at a quarter of it --
    by cubic-spline interpolation (``scipy.ndimage.map_coordinates``): rows are t (across the stripes),
    columns s. The contrast scan then reads line widths in metres from the wedge's own geometry."""
    from scipy import ndimage

    p = frame.pixel_m
    w0, _, length, n, _, (lox, loy) = _wedge_geometry(it)
    s_m = (np.arange(int(length / p)) + 0.5) * p
    t_m = np.arange(0.5 * w0, (2 * n - 1.5) * w0 + 1e-9, p / 4)  # fine across the stripes: max/min found
    r = np.sqrt(0.5)
    x = lox + r * (s_m[None, :] - t_m[:, None])
    y = loy + r * (s_m[None, :] + t_m[:, None])
    cols, rows = (x - frame.origin_m[0]) / p - 0.5, (y - frame.origin_m[1]) / p - 0.5
    if cols.min() < 0 or rows.min() < 0 or cols.max() > refl.shape[1] - 1 or rows.max() > refl.shape[0] - 1:
        raise Skip("outside the image")
    ts = ndimage.map_coordinates(np.asarray(refl, float), [rows, cols], order=3, mode="nearest")
    return ts, s_m, t_m


def wedge_item(ctx: AutoContext, it: dict) -> tuple[AutoItem, list[dict]]:
    """Hyperbolic wedge: the contrast scan over the stripes only (see :mod:`satchain.measure.auto`). A diagonal
    wedge is first resampled onto its own axes; its resolution is along the D135 diagonal."""
    refl, frame, threshold = ctx.refl, ctx.frame, ctx.wedge_threshold
    p = frame.pixel_m
    w0, x0, length, n, horizontal, (lox, loy) = _wedge_geometry(it)
    if str(it["orientation"]).lower() == "diagonal":
        ts, s_m, t_m = _diagonal_wedge_grid(refl, it, frame)
        fs = ctx.full_scale_refl
        return _scan_wedge(ts, s_m, t_m, it, w0, x0, n, t_m[1] - t_m[0], threshold, "D135", None, fs), []
    if w0 / p < 1.0:
        raise Skip(f"too small: the widest lines ({w0:g} m = {w0 / p:.2f} px) are finer than 1 px (Nyquist)")
    s_ax, t_ax = (0, 1) if horizontal else (1, 0)
    s_org, t_org = (lox, loy) if horizontal else (loy, lox)
    s0, s1 = frame.centres(s_org + 0.5 * p, s_org + length - 0.5 * p, s_ax)
    t0, t1 = frame.centres(t_org + 0.5 * w0, t_org + (2 * n - 1.5) * w0, t_ax)
    roi = (s0, t0, s1, t1) if horizontal else (t0, s0, t1, s1)
    frame.check_roi(roi)
    sub = refl[roi[1] : roi[3], roi[0] : roi[2]]
    ts = np.array(sub if horizontal else sub.T, dtype=float)  # rows = t (across the stripes), cols = s
    s_m = frame.origin_m[s_ax] + (np.arange(s0, s1) + 0.5) * p - s_org
    t_m = frame.origin_m[t_ax] + (np.arange(t0, t1) + 0.5) * p - t_org
    direction = "ALT" if horizontal else "ACT"
    return _scan_wedge(ts, s_m, t_m, it, w0, x0, n, p, threshold, direction, roi, ctx.full_scale_refl), []


def _scan_wedge(ts, s_m, t_m, it, w0, x0, n, p, threshold, direction, roi, full_scale=None) -> AutoItem:
    """The contrast scan on a wedge laid out as rows = t (across the stripes, spacing ``p`` m), columns = s
    (along it)."""
    w = w0 * x0 / (x0 + s_m)
    inside = (t_m[:, None] >= 0.5 * w[None, :]) & (t_m[:, None] <= (2 * n - 1.5) * w[None, :])
    count = inside.sum(axis=0)
    stop = int(np.argmax(count < 3)) if np.any(count < 3) else count.size
    if stop < 4:
        raise Skip(f"too small at {p:g} m pixels: fewer than 4 positions with 3 or more rows across the stripes")
    ts, inside, w, s_m = ts[:, :stop], inside[:, :stop], w[:stop], s_m[:stop]
    if not np.all(np.isfinite(ts[inside])):
        raise InputError("image: the wedge region contains NaN/inf values")
    fill = np.array([np.median(ts[inside[:, j], j]) for j in range(stop)])
    ts = np.where(inside, ts, fill[None, :])
    r = measure_wedge(
        ts if direction != "ACT" else ts.T,
        line_width_px=w / p,
        direction="ACT" if direction == "ACT" else "ALT",
        threshold=threshold,
        pixel_m=p,
        valid=inside if direction != "ACT" else inside.T,
        full_scale=full_scale,
    )
    summary = {
        "id": it["id"],
        "orientation": it["orientation"],
        "direction": direction,
        "roi_px": None if roi is None else list(roi),
        "threshold": r.threshold,
        "resolution_m": r.resolved_line_width_m,
        "resolution_m_std": r.resolved_line_width_m_std,
        "resolved_line_width_px": r.resolved_line_width_px,
        "resolved_line_width_px_std": r.resolved_line_width_px_std,
        "flags": list(r.flags),
        "resolved_position_px": r.resolved_position_px,
        "resolved_f_cy_per_px": r.resolved_f_cy_per_px,
        "resolved_f_cy_per_m_ground": r.resolved_f_cy_per_m_ground,
        "position_px": r.position_px,
        "position_m_along_wedge": s_m[r.position_px.astype(int)],
        "line_width_m": r.line_width_px * p,
        "line_width_px": r.line_width_px,
        "contrast": r.contrast,
    }
    return AutoItem(str(it["id"]), HyperbolicWedge.kind, r, to_jsonable(summary))
