"""The per-kind measurers of :func:`satchain.measure.auto.measure_auto` for slanted edges, Siemens stars and bar
targets (regions of interest: see that module's docstring).  Each takes the shared :class:`AutoContext` and one
truth item and returns ``(AutoItem, skipped)``; an item it cannot measure raises :class:`Skip`."""

from __future__ import annotations

import math
import re
from dataclasses import replace

import numpy as np

from satchain.errors import InputError
from satchain.measure._common import to_jsonable
from satchain.measure.auto._common import AutoContext, AutoItem, Frame, Skip, skip_entry
from satchain.measure.bars import measure_bars
from satchain.measure.bars._groups import renumber
from satchain.measure.edge import measure_edge
from satchain.measure.star import measure_star
from satchain.scene.targets import BarTarget, SiemensStar, SlantedEdge

__all__ = ["bars_item", "edge_item", "geometry_text", "star_item"]

_EDGE_MIN_PX = 16
_EDGE_MARGIN_PX = 3
_STAR_EDGE_PX = 2.0
_STAR_MIN_PX = 8.0
#: Under an image affine a bar group is measured while the drift of its bars' edges across its region lowers the
#: fundamental by at most 1 % (``sinc(drift / period) >= 0.99``: drift <= 0.078 period).
_BAR_MAX_LOSS = 0.01


def _wrap_deg(a: float) -> float:
    """Angle of an undirected line, wrapped into (-90, 90]."""
    a = (a + 90.0) % 180.0 - 90.0
    return 90.0 if a == -90.0 else a


def _to_truth_convention(angle_image_deg: float, measures: str) -> float:
    """measure_edge's angle (from +y towards +x) -> the truth's (``act``: the same; ``alt``: +x to +y)."""
    return _wrap_deg(angle_image_deg if measures == "act" else 90.0 - angle_image_deg)


def edge_item(ctx: AutoContext, it: dict) -> tuple[AutoItem, list[dict]]:
    """Slanted edge: the square shrunk by max(3 px, 10 %) on each side."""
    raw, frame = ctx.raw, ctx.frame
    x0, y0, x1, y1 = frame.inside(it["bbox_m"])
    side = min(x1 - x0, y1 - y0)
    margin = max(_EDGE_MARGIN_PX, int(math.ceil(0.1 * side)))
    roi = (x0 + margin, y0 + margin, x1 - margin, y1 - margin)
    if min(roi[2] - roi[0], roi[3] - roi[1]) < _EDGE_MIN_PX:
        raise Skip(
            f"too small at {frame.pixel_m:g} m pixels: the square is {side} px wide, its inner region "
            f"{max(0, side - 2 * margin)} px; need >= {_EDGE_MIN_PX} px"
        )
    frame.check_roi(roi)
    measures = str(it["measures"]).lower()
    step = frame.step_m(0 if measures == "act" else 1)  # the ground step along the edge normal's pixel axis
    r = measure_edge(raw, roi=roi, pixel_m=step, full_scale=ctx.full_scale)
    dx, dy = it["edge_direction"]
    truth_image = _wrap_deg(math.degrees(math.atan2(dx, dy)))
    warnings = list(r.warnings)
    if r.direction != measures.upper():
        warnings.append(f"the edge was measured as {r.direction} although the truth says {measures.upper()}")
    summary = {
        "id": it["id"],
        "roi_px": list(roi),
        "angle_deg": _to_truth_convention(r.angle_deg, measures),
        "angle_deg_truth": float(it["angle_deg"]),
        "angle_convention": "truth's: act = from +y towards +x, alt = from +x towards +y",
        "edge_angle_deg_image": r.angle_deg,
        "edge_angle_deg_image_truth": truth_image,
        "direction": r.direction,
        "direction_truth": measures.upper(),
        "mtf_at_nyquist": r.mtf_at_nyquist,
        "mtf_at_nyquist_sigma": r.mtf_at_nyquist_sigma,
        "mtf_sigma": r.mtf_sigma,
        "flags": list(r.flags),
        "mtf50_cy_per_px": r.mtf50_cy_per_px,
        "rer": r.rer,
        "overshoot": r.overshoot,
        "n_lines": r.n_lines,
        "fit_degree": r.fit_degree,  # the edge polynomial's degree: its slope at the mean line is angle_deg
        "warnings": warnings,
        "f_cy_per_px": r.f_cy_per_px,
        "f_cy_per_m_ground": r.f_cy_per_m_ground,
        "mtf": r.mtf,
        "lines": r.lines,  # each image line across the edge and where it crosses it (line-of-sight motion)
        "edge_position_px": r.edge_position_px,
        "mtf_as_imaged_at_nyquist": r.mtf_as_imaged_at_nyquist,  # the lines' displacements folded in (ISO)
        "los_motion_rms_px": r.los_motion_rms_px,  # the line-of-sight motion each line's location removed
    }
    if frame.affine is not None:  # the truth's direction through the image geometry: the angle the image shows
        a, b, d, e = frame.linear
        expected = _wrap_deg(math.degrees(math.atan2(a * dx + b * dy, d * dx + e * dy)))
        summary["angle_deg_expected"] = _to_truth_convention(expected, measures)
        summary["edge_angle_deg_image_expected"] = expected
    return AutoItem(str(it["id"]), SlantedEdge.kind, r, to_jsonable(summary)), []


def geometry_text(frame: Frame) -> str:
    """The image geometry in words: how far scene lines along y and x are turned from the pixel columns and
    rows, and the ALT ground step relative to the ACT one."""
    ty, tx = math.degrees(math.atan(frame.tilt(1))), math.degrees(math.atan(frame.tilt(0)))
    return (
        f"scene y-lines at {ty:+.2f} deg and x-lines at {tx:+.2f} deg to the pixel columns and rows, ALT/ACT "
        f"ground step {frame.step_m(1) / frame.step_m(0):.4f}"
    )


def _star_extent(frame: Frame) -> tuple[float, float]:
    """Half-extents (px) along x and y of the image of a star of unit radius (mean pixels): 1 on a plain grid,
    the ellipse's under an image affine."""
    if frame.affine is None:
        return 1.0, 1.0
    a, b, d, e = frame.linear
    k = math.sqrt(abs(a * e - b * d))
    return math.hypot(a, b) / k, math.hypot(d, e) / k


def star_item(ctx: AutoContext, it: dict) -> tuple[AutoItem, list[dict]]:
    """Siemens star: centre, radius and cycles from the truth; input modulation = amplitude / mean. Under an image
    affine the star is an ellipse: it is measured in its own frame through the affine, each direction at the
    image's frequency along it (``image_affine`` of :func:`~satchain.measure.star.measure_star`)."""
    refl, frame, calibrated = ctx.refl, ctx.frame, ctx.calibrated
    p = frame.pixel_m
    cycles = int(it["cycles"])
    xc, yc = frame.px(*it["center_m"])
    radius = frame.length_px(float(it["radius_m"])) - _STAR_EDGE_PX
    inner = frame.length_px(float(it.get("inner_radius_m", 0.0))) + 1.0
    if radius < _STAR_MIN_PX:
        raise Skip(f"too small at {p:g} m pixels: usable radius {radius:.1f} px < {_STAR_MIN_PX:g} px")
    ex, ey = _star_extent(frame)
    roi = (
        math.floor(xc - radius * ex) - 1,
        math.floor(yc - radius * ey) - 1,
        math.ceil(xc + radius * ex) + 2,
        math.ceil(yc + radius * ey) + 2,
    )
    frame.check_roi(roi)
    f_max = min(0.75, cycles / (2 * math.pi * max(inner, 2.0)))
    m0 = float(it["amplitude"]) / float(it["mean"]) if calibrated else None
    r = measure_star(
        refl,
        cycles=cycles,
        center=(xc - roi[0], yc - roi[1]),
        radius_px=radius,
        roi=roi,
        input_modulation=m0,
        f_max_cy_per_px=f_max,
        pixel_m=p,
        full_scale=ctx.full_scale_refl,
        image_affine=frame.affine,
        row_offsets_px=ctx.row_offsets_px,
    )
    summary = {
        "id": it["id"],
        "roi_px": list(roi),
        "cycles": cycles,
        "center_xy_px": [xc, yc],
        "radius_px": [float(r.radius_px.min()), float(r.radius_px.max())],
        "input_modulation": r.input_modulation,
        "input_modulation_from": "truth" if m0 is not None else r.input_modulation_from,
        "center_xy_px_measured": [r.center_xy_px[0] + roi[0], r.center_xy_px[1] + roi[1]],
        "center_std_px": r.center_std_px,
        "input_modulation_std": r.input_modulation_std,
        "mtf_at_nyquist": r.mtf_at_nyquist,
        "mtf_at_nyquist_std": r.mtf_at_nyquist_std,
        "f_cy_per_px": r.f_cy_per_px,
        "f_cy_per_m_ground": r.f_cy_per_m_ground,
        "mtf": r.mtf,
        "mtf_std": r.mtf_std,
        "mtf_all": r.mtf_all,
        "flags": list(r.flags),
    }
    return AutoItem(str(it["id"]), SiemensStar.kind, r, to_jsonable(summary)), []


def _group_roi(group: dict, frame: Frame, orientation: str):
    """Bar-group ROI: first to last bar centre across the bars, one bar width in from each end along them."""
    bars = np.asarray(group["bars_m"], dtype=float)
    b = float(group["bar_width_m"])
    across, along = (0, 1) if orientation == "act" else (1, 0)
    centres = 0.5 * (bars[:, across] + bars[:, across + 2])
    a_lo, a_hi = float(centres.min()), float(centres.max())
    lo, hi = float(bars[:, along].max()) + b, float(bars[:, along + 2].min()) - b
    return frame.centres_box((a_lo, lo, a_hi, hi) if orientation == "act" else (lo, a_lo, hi, a_hi))


def _period_px(frame: Frame, group: dict, orientation: str) -> float:
    """A group's period in pixels along the pixel axis across its bars."""
    return float(group["period_m"]) / frame.step_m(0 if orientation == "act" else 1)


def _bar_drift(frame: Frame, roi, orientation: str, period_px: float) -> str | None:
    """Why a group's bars are too tilted by the image geometry to measure (:data:`_BAR_MAX_LOSS`), or None."""
    if frame.affine is None:
        return None
    along = 1 if orientation == "act" else 0  # ACT bars run along y (the columns), ALT bars along x
    n = (roi[3] - roi[1]) if along == 1 else (roi[2] - roi[0])
    drift = abs(frame.tilt(along)) * max(n - 1, 0)
    loss = 1.0 - float(np.sinc(drift / period_px))
    if loss <= _BAR_MAX_LOSS:
        return None
    deg = math.degrees(math.atan(abs(frame.tilt(along))))
    return (
        f"sheared {deg:.2f} deg by the image geometry ({geometry_text(frame)}): the bars' edges drift {drift:.2f} px "
        f"across the group's {n} {'rows' if along == 1 else 'columns'}, lowering its CTF by {100 * loss:.1f} % "
        f"(> {100 * _BAR_MAX_LOSS:g} %): the bar measurement needs bars aligned with the pixel rows/columns"
    )


def bars_item(ctx: AutoContext, it: dict) -> tuple[AutoItem, list[dict]]:
    """Bar target: one ROI per group; groups beyond Nyquist or too small are skipped (listed)."""
    frame, calibrated = ctx.frame, ctx.calibrated
    orientation = str(it["orientation"]).lower()
    if int(it["n_bars"]) < 2:
        raise Skip("a single bar per group has no period to measure a CTF on")
    keep, rois, skipped = _measurable_groups(it, frame, orientation)
    if not keep:
        geo = [e["reason"] for e in skipped if "by the image geometry" in e["reason"]]
        if geo:  # (the group entries are not returned with a Skip: the target's reason names the geometry)
            raise Skip(f"no bar group is measurable ({len(geo)} of {len(skipped)} for the geometry; first: {geo[0]})")
        raise Skip(f"no bar group is measurable at {frame.pixel_m:g} m pixels (see the bar_group entries)")
    levels = (float(it["dark"]), float(it["bright"])) if calibrated else None
    direction = "ACT" if orientation == "act" else "ALT"
    r = _measure_kept(ctx, it, keep, rois, (direction, levels), skipped)
    r = replace(r, flags=tuple(renumber(r.flags, keep)))  # every group named by its index in the target's design
    groups = [it["groups"][k] for k in keep]
    periods_px = [_period_px(frame, g, orientation) for g in groups]
    summary = {
        "id": it["id"],
        "direction": direction,
        "periods_m": [float(g["period_m"]) for g in groups],
        "periods_px": periods_px,
        "f_cy_per_px": r.f_cy_per_px,
        "f_cy_per_m_ground": r.f_cy_per_m_ground,
        "ctf": r.ctf,
        "ctf_std": r.ctf_std,
        "ctf_correction": r.ctf_correction,
        "mtf": r.mtf,
        "mtf_std": r.mtf_std,
        "large_area_contrast": r.large_area_contrast,
        "levels_from": "truth" if levels is not None else r.levels_from,
        "flags": list(r.flags),
        "groups": _group_rows(r, keep, groups, periods_px, rois),
    }
    return AutoItem(str(it["id"]), BarTarget.kind, r, to_jsonable(summary)), skipped


def _measurable_groups(it: dict, frame: Frame, orientation: str) -> tuple[list, list, list]:
    """The groups resolvable and inside the image at the frame's pixel size: (their indices, their ROIs, the
    skip entries of the others)."""
    p = frame.pixel_m
    keep, rois, skipped = [], [], []
    for k, g in enumerate(it["groups"]):
        gid = f"{it['id']}/group_{k}"
        period_px = _period_px(frame, g, orientation)
        if period_px < 2.0:
            reason = f"period {g['period_m']:g} m = {period_px:.2f} px < 2 px: beyond the Nyquist frequency"
            skipped.append(skip_entry(gid, "bar_group", reason))
            continue
        roi = _group_roi(g, frame, orientation)
        if roi[2] - roi[0] < 2 or roi[3] - roi[1] < 2:
            skipped.append(skip_entry(gid, "bar_group", f"region {roi} is under 2 px on a side at {p:g} m pixels"))
            continue
        try:
            frame.check_roi(roi)
        except Skip as exc:
            skipped.append(skip_entry(gid, "bar_group", str(exc)))
            continue
        why = _bar_drift(frame, roi, orientation, period_px)
        if why is not None:
            skipped.append(skip_entry(gid, "bar_group", why))
            continue
        keep.append(k)
        rois.append(roi)
    return keep, rois, skipped


def _measure_kept(ctx: AutoContext, it: dict, keep: list, rois: list, opts: tuple, skipped: list):
    """:func:`measure_bars` on the kept groups; a group refused (no bars at its period, ...) is listed in
    ``skipped``, dropped from ``keep`` and ``rois`` (in place), and the others are measured again.
    ``opts = (direction, levels)``."""
    direction, levels = opts
    orientation = "act" if direction == "ACT" else "alt"
    p = ctx.frame.step_m(0 if direction == "ACT" else 1)
    while True:
        periods_px = [_period_px(ctx.frame, it["groups"][k], orientation) for k in keep]
        try:
            r = measure_bars(
                ctx.refl,
                periods_px=periods_px,
                group_rois=rois,
                direction=direction,
                levels=levels,
                pixel_m=p,
                bars_per_group=int(it["n_bars"]),
                full_scale=ctx.full_scale_refl,
            )
        except InputError as exc:
            bad = re.search(r"(?:group_rois|periods_px)\[(\d+)\]", str(exc))
            if bad is None or len(keep) < 2:
                raise
            j = int(bad.group(1))
            skipped.append(skip_entry(f"{it['id']}/group_{keep[j]}", "bar_group", f"refused: {_design(exc, keep)}"))
            del keep[j], rois[j]
            continue
        if not r.refused:
            return r
        for j, why in sorted(r.refused, reverse=True):  # refused alone by measure_bars: listed, the rest remeasured
            skipped.append(skip_entry(f"{it['id']}/group_{keep[j]}", "bar_group", f"refused: {_design(why, keep)}"))
            del keep[j], rois[j]


def _design(msg, keep: list) -> str:
    """A refusal of :func:`measure_bars` with its groups named by their index in the target's design (``keep``:
    the design index of each group it was given)."""
    return re.sub(r"(group_rois|periods_px)\[(\d+)\]", lambda m: f"{m.group(1)}[{keep[int(m.group(2))]}]", str(msg))


def _group_rows(r, keep: list, groups: list, periods_px: list, rois: list) -> list[dict]:
    """One summary row per measured group."""
    return [
        {
            "group": k,
            "period_m": float(g["period_m"]),
            "period_px": pp,
            "roi_px": list(roi),
            "ctf": c,
            "ctf_std": cs,
            "mtf": m,
            "phase_px": ph,
            "ctf_correction": None if r.ctf_correction is None else float(r.ctf_correction[j]),
            "flags": [f for f in r.flags if f.startswith(f"group {k}:")],
        }
        for j, (k, g, pp, roi, c, cs, m, ph) in enumerate(
            zip(keep, groups, periods_px, rois, r.ctf, r.ctf_std, r.mtf, r.phase_px, strict=True)
        )
    ]
