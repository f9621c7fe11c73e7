"""``satchain measure edge|star|bars|wedge``: one target in a region of an image file.

The commands are plain functions (wrapped by :func:`satchain.cli._common.handle_errors`); they are registered on
the ``measure`` sub-app in one place, :mod:`satchain.cli.measure`.  Their shared options come from
:mod:`satchain.cli.options`, their printing and writing from :mod:`satchain.cli.output`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from satchain._safety import check_dir_outputs, check_star_radius
from satchain.cli._common import handle_errors, parse_numbers, print_warning
from satchain.cli.options import (
    BandOpt,
    FitDegreeOpt,
    FrequencyAxisOpt,
    FullScaleOpt,
    ImageArg,
    JsonOpt,
    NodataOpt,
    OriginOpt,
    OutOpt,
    PixelOpt,
    RoiOpt,
    ThresholdOpt,
    TruthOpt,
    ground_fields,
    load_image,
    measuring,
    parse_fit_degree,
    parse_frequency_axis,
    parse_full_scale,
    parse_origin,
    parse_roi,
    parse_valid,
    read_truth,
)
from satchain.cli.output import (
    axis_words,
    curve_table,
    emit,
    kv_table,
    one_plot,
    pm,
    print_flags,
    print_ground,
    wide_console,
)
from satchain.errors import ConfigError

__all__ = ["bars", "edge", "star", "wedge"]

# ------------------------------------------------------------------------------------------------------ edge


def _edge_tables(r, name: str, p: float | None, note: str | None = None) -> None:
    c = wide_console()
    rows = [
        ("edge angle (deg from y/ALT)", r.angle_deg),
        ("MTF direction", r.direction),
        ("MTF at Nyquist", f"{r.mtf_at_nyquist:.4f} +- {r.mtf_at_nyquist_sigma:.4f} (1 sigma, noise)"),
        ("MTF50 (cy/px)", r.mtf50_cy_per_px),
        ("RER", r.rer),
        ("overshoot H", r.overshoot),
        ("edge contrast", r.contrast),
        ("noise sigma", r.noise_sigma),
        ("contrast-to-noise", r.cnr),
        ("lines used", r.n_lines),
        ("edge fit degree", r.fit_degree),
        ("edge curvature (1/px)", r.curvature_per_px),
        ("ESF sample spacing (px)", r.bin_width_px),
        ("quality flags", ", ".join(r.flags) if r.flags else "none"),
    ]
    if "line_of_sight_motion" in r.flags:  # the headline has each line located; the edge as imaged beside it
        rows.insert(3, ("MTF at Nyquist as imaged (ISO, lines folded)", f"{r.mtf_as_imaged_at_nyquist:.4f}"))
        rows.insert(4, ("line-of-sight motion removed (px rms)", r.los_motion_rms_px))
    if p and r.mtf50_cy_per_px is not None:
        rows.insert(4, ("MTF50 (cy/m ground)", r.mtf50_cy_per_px / p))
    rows.insert(0, ("frequency axis", axis_words(r.frequency_axis, r.frequency_scale, r.angle_deg)))
    c.print(kv_table(f"slanted edge: {name}", rows))
    print_ground(p, note)
    sig = r.mtf_sigma if r.mtf_sigma is not None else 0 * r.mtf
    title = "MTF along the edge normal" if r.frequency_axis == "normal" else f"MTF along the image {_ROW[r.direction]}"
    c.print(curve_table(title, r.f_cy_per_px, {"MTF": r.mtf, "1 sigma": sig}, p))
    for w in r.warnings:
        print_warning(w, c)


_ROW = {"ACT": "row", "ALT": "column"}


@handle_errors
def edge(
    image: ImageArg,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    band: BandOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
    fit_degree: FitDegreeOpt = "auto",
    full_scale: FullScaleOpt = None,
    nodata: NodataOpt = None,
    frequency_axis: FrequencyAxisOpt = "normal",
) -> None:
    """Slanted-edge MTF (ISO 12233 e-SFR, improved): MTF +- 1 sigma, MTF at Nyquist, MTF50, RER, overshoot.

    The region must hold one straight (or gently curved) edge; stripes, corners, no edge and clipped
    plateaus are refused (exit 2).  Quality flags (near-critical angle, curvature, illumination gradient,
    low contrast-to-noise, clipping) are printed and listed in the JSON (``flags``, ``warnings``).
    With a metric pixel size (``--pixel-m`` or the raster's projected transform) every frequency is also given
    in cy/m on the ground.  ``--frequency-axis row`` gives the MTF on MTF_Estimator's axis (along the image
    row / column: ``f_row = cos(tilt) f_normal``, the factor printed and in the JSON as ``frequency_scale``).
    """
    from satchain.measure.edge import measure_edge
    from satchain.report.measure_plots import plot_edge

    check_dir_outputs(out, ["edge.json", "edge.png"], {"IMAGE": image})
    data, p, meta = load_image(image, pixel_m, band)
    region = parse_roi("--roi", roi)
    fs = parse_full_scale(full_scale, data, meta)
    axis, deg = parse_frequency_axis(frequency_axis), parse_fit_degree(fit_degree)
    valid = parse_valid(data, nodata, meta, image)
    with measuring(image, valid):
        r = measure_edge(data, roi=region, pixel_m=p, fit_degree=deg, full_scale=fs, valid=valid, frequency_axis=axis)
    ground = ground_fields(p, meta)
    payload = {"image": str(image), "roi": region, **ground, **r.to_dict()}
    emit(
        payload, as_json, out, "edge", lambda d: one_plot(plot_edge, r, d / "edge.png"),
        lambda: _edge_tables(r, image.name, p, ground.get("pixel_m_note")),
    )  # fmt: skip


# ------------------------------------------------------------------------------------------------------ star


def _star_tables(r, name: str, region, p: float | None, note: str | None = None) -> None:
    from satchain.measure.star import STAR_DIRECTIONS

    con = wide_console()
    ox, oy = (region[0], region[1]) if region is not None else (0, 0)
    cx, cy = r.center_xy_px[0] + ox, r.center_xy_px[1] + oy
    csd = "" if r.center_std_px is None else f" ± ({r.center_std_px[0]:.2g}, {r.center_std_px[1]:.2g})"
    rows = [
        ("cycles (checked)", r.cycles),
        (f"centre X,Y px ({r.center_from})", f"{cx:.3f}, {cy:.3f}{csd}"),
        (f"input modulation ({r.input_modulation_from})", pm(r.input_modulation, r.input_modulation_std)),
    ]
    rows += [
        (f"MTF at Nyquist, {k}", pm(r.mtf_at_nyquist[k], (r.mtf_at_nyquist_std or {}).get(k))) for k in STAR_DIRECTIONS
    ]
    con.print(kv_table(f"Siemens star: {name}", rows))
    cols = {**r.mtf, "± (all)": r.mtf_all_std}
    con.print(curve_table("MTF per direction (1-sigma of the all-angle curve)", r.f_cy_per_px, cols, p, 0.05))
    print_ground(p, note)
    print_flags(r.flags)


def _check_center_inside(text: str, c, shape, roi_text, region) -> None:
    """Refuse a ``--center`` outside the image (or outside ``--roi``), naming both (issue 29)."""
    ny, nx = shape[-2:]
    x0, y0, x1, y1 = (0, 0, nx, ny) if region is None else region
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, nx), min(y1, ny)
    if not (x0 <= c[0] <= x1 - 1 and y0 <= c[1] <= y1 - 1):
        where = "the image" if region is None else f"--roi {roi_text}"
        raise ConfigError(
            f"--center = {text}: outside {where} (x in [{x0:g}, {x1 - 1:g}], y in [{y0:g}, {y1 - 1:g}] px); give "
            "the star's approximate centre X,Y in whole-image pixels"
        )


@handle_errors
def star(
    image: ImageArg,
    cycles: Annotated[int, typer.Option("--cycles", help="periods per revolution of the sinusoidal star")],
    center: Annotated[
        str | None, typer.Option("--center", help="approximate star centre X,Y in image pixels (refined)")
    ] = None,
    refine_center: Annotated[
        bool, typer.Option("--refine-center/--no-refine-center", help="estimate/refine the centre from the data")
    ] = True,
    radius: Annotated[float | None, typer.Option("--radius", help="outer radius used (px)")] = None,
    input_modulation: Annotated[
        float | None,
        typer.Option("--input-modulation", help="the star's own modulation; default: outer radii"),
    ] = None,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    band: BandOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
    full_scale: FullScaleOpt = None,
) -> None:
    """Siemens-star MTF per direction (ACT, ALT, diagonals). ``--center`` is in whole-image pixels."""
    from satchain.measure.star import measure_star
    from satchain.report.measure_plots import plot_star

    check_dir_outputs(out, ["star.json", "star.png"], {"IMAGE": image})
    data, p, meta = load_image(image, pixel_m, band)
    check_star_radius(radius, data.shape)
    region = parse_roi("--roi", roi)
    c: list[float] | None = None
    if center is not None:
        c = parse_numbers("--center", center, 2)
        _check_center_inside(center, c, data.shape, roi, region)
    if c is not None and region is not None:
        c = [c[0] - region[0], c[1] - region[1]]
    r = measure_star(
        data, cycles=cycles, center=c, radius_px=radius, roi=region, input_modulation=input_modulation,
        pixel_m=p, refine_center=refine_center, full_scale=parse_full_scale(full_scale, data, meta),
    )  # fmt: skip
    payload = {"image": str(image), "roi": region, **ground_fields(p, meta), **r.to_dict()}
    emit(
        payload, as_json, out, "star", lambda d: one_plot(plot_star, r, d / "star.png"),
        lambda: _star_tables(r, image.name, region, p, payload.get("pixel_m_note")),
    )  # fmt: skip


# ------------------------------------------------------------------------------------------------------ bars


def _bars_tables(r, name: str, p: float | None, note: str | None = None) -> None:
    t = Table(title=f"bar target ({r.direction}): {name}")
    ground_col = ["f cy/m ground"] if p else []
    for col in ("period px", "f cy/px", *ground_col, "CTF ± 1σ", "of which correction",
                "MTF (Coltman inverse) ± 1σ", "bar phase px"):  # fmt: skip
        t.add_column(col, justify="right")
    refused = dict(r.refused)
    for k in range(r.f_cy_per_px.size):
        ground = [f"{r.f_cy_per_px[k] / p:.3f}"] if p else []
        if k in refused:  # no number for a refused group: say so in the row
            t.add_row(f"{r.periods_px[k]:.3g}", f"{r.f_cy_per_px[k]:.4f}", *ground, "refused", "-", "refused", "-")
            continue
        mtf = None if r.mtf[k] != r.mtf[k] else float(r.mtf[k])
        t.add_row(
            f"{r.periods_px[k]:.3g}",
            f"{r.f_cy_per_px[k]:.4f}",
            *ground,
            pm(float(r.ctf[k]), float(r.ctf_std[k])),
            "-" if r.ctf_correction is None else f"{float(r.ctf_correction[k]):+.4f}",
            pm(mtf, float(r.mtf_std[k])),
            f"{r.phase_px[k]:.3f}",
        )
    wide_console().print(t)
    wide_console().print(
        f"large-area contrast {pm(r.large_area_contrast, r.large_area_contrast_std)} ({r.levels_from})",
        highlight=False,
    )
    for k, reason in r.refused:
        wide_console().print(f"group {k} (period {r.periods_px[k]:.3g} px) refused: {reason}", highlight=False)
    print_ground(p, note)
    print_flags(r.flags)


def _bar_group_rois(periods: list[float], periods_px: str, group_roi, roi, shape) -> list:
    """One ROI per group: ``--group-roi`` (repeated), or one ``--roi`` (default: the image) for one group."""
    if group_roi:
        if roi is not None:
            raise ConfigError("--roi and --group-roi: give one ROI per group with --group-roi, or one --roi")
        return [parse_roi("--group-roi", g) for g in group_roi]
    if len(periods) == 1:
        return [parse_roi("--roi", roi) or (0, 0, shape[-1], shape[0])]
    raise ConfigError(f"--periods-px = {periods_px!r}: {len(periods)} groups need one --group-roi each")


@handle_errors
def bars(
    image: ImageArg,
    periods_px: Annotated[str, typer.Option("--periods-px", help="period of each group (px), P1,P2,...")],
    group_roi: Annotated[
        list[str] | None,
        typer.Option(
            "--group-roi",
            help="X0,Y0,X1,Y1 of one group, across the bars from the first to the last bar centre, no plate "
            "(repeat, one per period)",
        ),
    ] = None,
    direction: Annotated[str, typer.Option("--direction", help="ACT: bars along y; ALT: bars along x")] = "ACT",
    levels: Annotated[
        str | None,
        typer.Option("--levels", help="large-area DARK,BRIGHT levels; default: the widest group if flat-topped"),
    ] = None,
    bars_per_group: Annotated[
        int,
        typer.Option(
            "--bars-per-group",
            help="bright bars in each group (3: USAF-style and the paper's targets); 0: a long grating, whose "
            "CTF is not corrected for a finite group",
        ),
    ] = 3,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    band: BandOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
    full_scale: FullScaleOpt = None,
) -> None:
    """Bar-target CTF per group (the square-wave CTF: with 3 or more groups, corrected for the finite group,
    aliased harmonics and grid phase through the target's joint MTF) and the MTF from the inverse Coltman
    series."""
    from satchain.measure.bars import measure_bars
    from satchain.report.measure_plots import plot_bars

    check_dir_outputs(out, ["bars.json", "bars.png"], {"IMAGE": image})
    data, p, meta = load_image(image, pixel_m, band)
    periods = parse_numbers("--periods-px", periods_px)
    rois = _bar_group_rois(periods, periods_px, group_roi, roi, data.shape)
    lv = None if levels is None else tuple(parse_numbers("--levels", levels, 2))
    if bars_per_group == 1 or bars_per_group < 0:
        raise ConfigError(
            f"--bars-per-group = {bars_per_group}: need >= 2 bright bars per group, or 0 for a long grating"
        )
    r = measure_bars(
        data, periods_px=periods, group_rois=rois, direction=direction.upper(), levels=lv, pixel_m=p,
        bars_per_group=bars_per_group or None, full_scale=parse_full_scale(full_scale, data, meta),
    )  # fmt: skip
    payload = {"image": str(image), "group_rois": rois, **ground_fields(p, meta), **r.to_dict()}
    emit(
        payload, as_json, out, "bars", lambda d: one_plot(plot_bars, r, d / "bars.png"),
        lambda: _bars_tables(r, image.name, p, payload.get("pixel_m_note")),
    )  # fmt: skip


# ----------------------------------------------------------------------------------------------------- wedge


def _line_widths(start_px: float, end_px: float, n: int, profile: str):
    """Line width at positions 0..n-1 along the wedge: ``linear`` in position, or ``hyperbolic`` (1/w linear,
    the ``y = A / x`` wedge of the paper: w = start at position 0 and end at position n - 1)."""
    import numpy as np

    from satchain._validate import check_choice, check_positive

    check_choice("--profile", profile, ("hyperbolic", "linear"))
    a, b = check_positive("--line-width-start-px", start_px), check_positive("--line-width-end-px", end_px)
    if n < 2:
        raise ConfigError(f"--roi: {n} position(s) along the wedge; need at least 2")
    u = np.arange(n) / (n - 1)
    return a + (b - a) * u if profile == "linear" else 1.0 / (1.0 / a + (1.0 / b - 1.0 / a) * u)


def _wedge_from_truth(data, truth_path: Path, item_id: str | None, p, origin, threshold: float, full_scale=None):
    """The wedge of a truth file, measured as ``measure auto`` does; returns (WedgeResult, summary, pixel_m)."""
    from satchain.measure.auto import measure_auto
    from satchain.scene.targets import HyperbolicWedge

    truth = read_truth(truth_path)
    wedges = [str(it.get("id")) for it in truth.get("items", []) if it.get("kind") == HyperbolicWedge.kind]
    if item_id is None:
        if len(wedges) != 1:
            raise ConfigError(f"--id: the truth file has {len(wedges)} hyperbolic wedges {wedges}; name one")
        item_id = wedges[0]
    elif item_id not in wedges:
        raise ConfigError(f"--id = {item_id!r}: not a hyperbolic wedge of the truth file; choose from {wedges}")
    res = measure_auto(
        data, truth, pixel_m=p, origin_m=origin, ids=[item_id], wedge_threshold=threshold, full_scale=full_scale
    )
    found = res.by_kind(HyperbolicWedge.kind)
    if not found:
        raise ConfigError(f"wedge {item_id!r} not measured: {res.skipped[0]['reason']}")
    return found[0].result, found[0].summary, res.pixel_m


def _wedge_from_widths(data, roi, start_px, end_px, profile: str, direction: str, threshold: float, p, full_scale=None):
    """The wedge in ``--roi`` (default: the image) with line widths from start to end; returns (result, dict)."""
    from satchain.measure.wedge import measure_wedge

    if start_px is None or end_px is None:
        raise ConfigError("wedge: give --line-width-start-px and --line-width-end-px, or --truth TRUTH.json")
    region = parse_roi("--roi", roi) or (0, 0, data.shape[-1], data.shape[0])
    axis = region[2] - region[0] if direction.upper() == "ALT" else region[3] - region[1]
    lw = _line_widths(start_px, end_px, axis, profile)
    r = measure_wedge(
        data, line_width_px=lw, direction=direction.upper(), roi=region, threshold=threshold, pixel_m=p,
        full_scale=full_scale,
    )  # fmt: skip
    return r, {"roi": region, "profile": profile, **r.to_dict()}


def _wedge_tables(r, name: str, p: float | None = None, note: str | None = None) -> None:
    rows = [
        ("direction (resolution)", r.direction),
        ("threshold", r.threshold),
        ("resolved line width (px)", pm(r.resolved_line_width_px, r.resolved_line_width_px_std)),
        ("resolved line width (m)", pm(r.resolved_line_width_m, r.resolved_line_width_m_std)),
        ("resolved frequency (cy/px)", r.resolved_f_cy_per_px),
        ("resolved frequency (cy/m ground)", r.resolved_f_cy_per_m_ground),
    ]
    wide_console().print(kv_table(f"hyperbolic wedge: {name}", rows))
    print_ground(p, note)
    print_flags(r.flags)


@handle_errors
def wedge(
    image: ImageArg,
    line_width_start_px: Annotated[
        float | None,
        typer.Option("--line-width-start-px", help="line width at the ROI's first position (px)"),
    ] = None,
    line_width_end_px: Annotated[
        float | None, typer.Option("--line-width-end-px", help="line width at the ROI's last position (px)")
    ] = None,
    profile: Annotated[
        str, typer.Option("--profile", help="hyperbolic (1/width linear in position) or linear")
    ] = "hyperbolic",
    direction: Annotated[
        str, typer.Option("--direction", help="ALT: stripes along x, scan along x; ACT: the transpose")
    ] = "ALT",
    threshold: ThresholdOpt = 0.15,
    truth: TruthOpt = None,
    item_id: Annotated[str | None, typer.Option("--id", help="wedge id in the truth file")] = None,
    origin_m: OriginOpt = None,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    band: BandOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
    full_scale: FullScaleOpt = None,
) -> None:
    """Hyperbolic-wedge contrast scan (the paper's): resolvable line width where the contrast falls to 15 %.

    Geometry either from ``--truth`` (exact: only the rows inside the fanning stripes count), or from
    ``--line-width-start-px/--line-width-end-px`` over the ROI (which must hold the stripes only), position 0
    being the ROI's first column (ALT) or row (ACT).
    """
    from satchain.report.measure_plots import plot_wedge

    check_dir_outputs(out, ["wedge.json", "wedge.png"], {"IMAGE": image, "--truth": truth})
    data, p, meta = load_image(image, pixel_m, band)
    fs = parse_full_scale(full_scale, data, meta)
    if truth is not None:
        if roi is not None or line_width_start_px is not None or line_width_end_px is not None:
            raise ConfigError("--truth: the geometry comes from the truth file; drop --roi and --line-width-*")
        r, summary, p = _wedge_from_truth(data, truth, item_id, p, parse_origin(origin_m, meta), threshold, fs)
        payload = {"image": str(image), "truth": str(truth), **ground_fields(p, meta), **summary}
    else:
        r, summary = _wedge_from_widths(
            data, roi, line_width_start_px, line_width_end_px, profile, direction, threshold, p, fs
        )
        payload = {"image": str(image), "roi": summary.pop("roi"), **ground_fields(p, meta), **summary}
    emit(
        payload, as_json, out, "wedge", lambda d: one_plot(plot_wedge, r, d / "wedge.png", pixel_m=p),
        lambda: _wedge_tables(r, image.name, p, payload.get("pixel_m_note")),
    )  # fmt: skip
