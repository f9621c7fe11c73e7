"""The hyperbolic-wedge measurer of :func:`satchain.measure.auto.measure_auto`: the paper's contrast scan over the
stripes only (see that module's docstring), a diagonal wedge first resampled onto its own axes."""

from __future__ import annotations

import numpy as np

from satchain.errors import InputError
from satchain.measure._common import to_jsonable
from satchain.measure.auto._common import AutoContext, AutoItem, Frame, Skip
from satchain.measure.auto._items import geometry_text
from satchain.measure.wedge import measure_wedge
from satchain.scene.targets import HyperbolicWedge

__all__ = ["wedge_item"]

#: Under an image affine a horizontal or vertical wedge is measured while its stripes drift across by at most
#: this over the wedge's length, and the position along the wedge changes by at most this (px) down a column
#: of its stripes: the scan then reads each column at one position, the stripes where the truth puts them.
_WEDGE_MAX_PX = 0.25


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
    cols, rows = frame.px(x, y)  # through the image geometry, when it has one
    if cols.min() < 0 or rows.min() < 0 or cols.max() > refl.shape[1] - 1 or rows.max() > refl.shape[0] - 1:
        raise Skip("outside the image")
    ts = ndimage.map_coordinates(np.asarray(refl, float), [rows, cols], order=3, mode="nearest")
    return ts, s_m, t_m


def wedge_item(ctx: AutoContext, it: dict) -> tuple[AutoItem, list[dict]]:
    """Hyperbolic wedge: the contrast scan over the stripes only (see :mod:`satchain.measure.auto`). A diagonal
    wedge is first resampled onto its own axes; its resolution is along the D135 diagonal."""
    refl, frame, threshold = ctx.refl, ctx.frame, ctx.wedge_threshold
    w0, x0, length, n, horizontal, (lox, loy) = _wedge_geometry(it)
    if str(it["orientation"]).lower() == "diagonal":
        ts, s_m, t_m = _diagonal_wedge_grid(refl, it, frame)
        fs = ctx.full_scale_refl
        return _scan_wedge(ts, s_m, t_m, it, w0, x0, n, t_m[1] - t_m[0], threshold, "D135", None, fs), []
    s_ax, t_ax = (0, 1) if horizontal else (1, 0)
    p, ps = frame.step_m(t_ax), frame.step_m(s_ax)  # the ground steps across and along the stripes
    if w0 / p < 1.0:
        raise Skip(f"too small: the widest lines ({w0:g} m = {w0 / p:.2f} px) are finer than 1 px (Nyquist)")
    s_org, t_org = (lox, loy) if horizontal else (loy, lox)
    s_lo, s_hi = s_org + 0.5 * ps, s_org + length - 0.5 * ps
    t_lo, t_hi = t_org + 0.5 * w0, t_org + (2 * n - 1.5) * w0
    roi = frame.centres_box((s_lo, t_lo, s_hi, t_hi) if horizontal else (t_lo, s_lo, t_hi, s_hi))
    frame.check_roi(roi)
    _check_wedge_geometry(frame, roi, s_ax)
    sub = refl[roi[1] : roi[3], roi[0] : roi[2]]
    ts = np.array(sub if horizontal else sub.T, dtype=float)  # rows = t (across the stripes), cols = s
    xs, ys = frame.centres_m(roi)  # s and t of each column / row: along the middle row / column
    mid_row, mid_col = xs[xs.shape[0] // 2, :], ys[:, ys.shape[1] // 2]
    s_m = (mid_row if horizontal else mid_col) - s_org
    t_m = (mid_col if horizontal else mid_row) - t_org
    direction = "ALT" if horizontal else "ACT"
    return _scan_wedge(ts, s_m, t_m, it, w0, x0, n, p, threshold, direction, roi, ctx.full_scale_refl), []


def _check_wedge_geometry(frame: Frame, roi, s_ax: int) -> None:
    """Refuse a wedge whose stripes the image geometry turns from the pixel axes by more than
    :data:`_WEDGE_MAX_PX` over its region (see there)."""
    if frame.affine is None:
        return
    n_s = (roi[2] - roi[0]) if s_ax == 0 else (roi[3] - roi[1])
    n_t = (roi[3] - roi[1]) if s_ax == 0 else (roi[2] - roi[0])
    drift, mix = abs(frame.tilt(s_ax)) * max(n_s - 1, 0), abs(frame.mix(s_ax)) * max(n_t - 1, 0)
    if max(drift, mix) > _WEDGE_MAX_PX:
        raise Skip(
            f"sheared by the image geometry ({geometry_text(frame)}): over the wedge's region its stripes drift "
            f"{drift:.2f} px across and its positions {mix:.2f} px along (> {_WEDGE_MAX_PX} px): the contrast scan "
            "needs stripes aligned with the pixel rows/columns"
        )


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
