"""``satchain measure``: image-quality measurements from image files (a typer sub-app, mounted by cli.py).

Commands: ``edge``, ``star``, ``bars``, ``wedge`` (one target in a region) and ``auto`` (every target of a
scene, from its truth file).  Images: TIFF (float or integer), PNG (8/16-bit) and NPY, read by
:func:`satchain.io.read_image`; the ground pixel size comes from ``--pixel-m`` or the file's metadata.
Regions are ``X0,Y0,X1,Y1`` in pixels (x = column, y = row), half-open.  ``--json`` prints the result as JSON;
``-o DIR`` writes ``<command>.json`` and a figure there.  Bad input: one line on stderr, exit status 2.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from satchain._cli_common import handle_errors, parse_numbers, print_warning
from satchain._safety import check_dir_outputs, check_star_radius
from satchain.errors import ConfigError, SatchainIOError

__all__ = ["measure_app"]

measure_app = typer.Typer(
    name="measure",
    help="Measure image quality (slanted edge, Siemens star, bar targets, hyperbolic wedge) from images.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

ImageArg = Annotated[Path, typer.Argument(help="image: .tif/.tiff (float or integer), .png (8/16-bit) or .npy")]
RoiOpt = Annotated[
    str | None, typer.Option("--roi", help="region X0,Y0,X1,Y1 in pixels (x = column, y = row; half-open)")
]
PixelOpt = Annotated[
    float | None, typer.Option("--pixel-m", help="ground pixel size (m); default: the file's metadata")
]
JsonOpt = Annotated[bool, typer.Option("--json", help="print JSON instead of tables")]
OutOpt = Annotated[Path | None, typer.Option("-o", "--out", help="write the results JSON and a figure here")]


def _console() -> Console:
    return Console(width=max(shutil.get_terminal_size((120, 40)).columns, 110))


_handle_errors = handle_errors


_numbers = parse_numbers


def _roi(name: str, text: str | None):
    """``X0,Y0,X1,Y1`` -> a tuple of 4 ints (or None)."""
    if text is None:
        return None
    vals = _numbers(name, text, 4)
    if any(v != int(v) for v in vals):
        raise ConfigError(f"{name} = {text!r}: must be four integers X0,Y0,X1,Y1 (pixels)")
    return tuple(int(v) for v in vals)


def _load(path: Path, pixel_m: float | None):
    """Read an image; returns (array, pixel_m or None, metadata)."""
    from satchain._validate import check_positive
    from satchain.io import read_image

    image, meta = read_image(path)
    if pixel_m is not None:
        pixel_m = check_positive("--pixel-m", pixel_m)
    elif meta.get("pixel_m") is not None:
        pixel_m = float(meta["pixel_m"])
    elif "invalid_pixel_m" in meta:  # a bad pixel size in the file is refused, never silently dropped
        raise ConfigError(f"IMAGE {str(path)!r}: its pixel size {meta['invalid_pixel_m']!r} is not a ground pixel "
                          "size in (0, 1e6] m; give --pixel-m")  # fmt: skip
    return image, pixel_m, meta


def _emit(payload: dict, as_json: bool, out: Path | None, name: str, plot, table) -> None:
    """Print (JSON or tables) and write ``out/name.json`` + ``out/name.png`` (atomically)."""
    text = json.dumps(payload, indent=2, allow_nan=False)
    written = []
    if out is not None:
        from satchain.report._save import write_text

        try:
            out.mkdir(parents=True, exist_ok=True)
            write_text(out / f"{name}.json", text + "\n")
            written = [out / f"{name}.json", *plot(out)]
        except OSError as exc:
            raise SatchainIOError(f"--out = {str(out)!r}: cannot write: {exc}") from None
    if as_json:
        print(text)
        return
    table()
    if written:
        _console().print("wrote " + ", ".join(str(p) for p in written), highlight=False)


def _fmt(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def _kv_table(title: str, rows: list[tuple[str, Any]]) -> Table:
    t = Table(title=title)
    t.add_column("quantity")
    t.add_column("value", justify="right")
    for k, v in rows:
        t.add_row(k, _fmt(v))
    return t


def _curve_table(title: str, f, columns: dict, pixel_m: float | None, step: float = 0.1) -> Table:
    """A few rows of curves sampled at multiples of ``step`` cy/px."""
    import numpy as np

    f = np.asarray(f, dtype=float)
    t = Table(title=title)
    t.add_column("f cy/px", justify="right")
    if pixel_m:
        t.add_column("f cy/m ground", justify="right")
    for k in columns:
        t.add_column(k, justify="right")
    for fk in np.arange(step, f.max() + 1e-9, step):
        if fk < f.min() - 1e-9:
            continue
        vals = [float(np.interp(fk, f, np.asarray(c, dtype=float))) for c in columns.values()]
        cells = [f"{fk:.2f}", *([f"{fk / pixel_m:.3f}"] if pixel_m else []), *[f"{v:.4f}" for v in vals]]
        t.add_row(*cells)
    return t


@measure_app.command()
@_handle_errors
def edge(
    image: ImageArg,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
    fit_degree: Annotated[
        str,
        typer.Option(
            "--fit-degree",
            help="degree of the edge-position fit: auto (chosen from the data; follows curved edges), 1, 2 or 3",
        ),
    ] = "auto",
) -> None:
    """Slanted-edge MTF (ISO 12233 e-SFR, improved): MTF +- 1 sigma, MTF at Nyquist, MTF50, RER, overshoot.

    The region must hold one straight (or gently curved) edge; stripes, corners, no edge and clipped
    plateaus are refused (exit 2).  Quality flags (near-critical angle, curvature, illumination gradient,
    low contrast-to-noise, clipping) are printed and listed in the JSON (``flags``, ``warnings``).
    """
    from satchain.measure.edge import measure_edge
    from satchain.report.measure_plots import plot_edge

    check_dir_outputs(out, ["edge.json", "edge.png"], {"IMAGE": image})
    data, p, _ = _load(image, pixel_m)
    region = _roi("--roi", roi)
    if fit_degree.strip().lower() not in ("auto", "1", "2", "3"):
        raise ConfigError(f"--fit-degree = {fit_degree!r}: must be auto, 1, 2 or 3")
    r = measure_edge(data, roi=region, pixel_m=p, fit_degree=fit_degree.strip().lower())
    payload = {"image": str(image), "roi": region, "pixel_m": p, **r.to_dict()}

    def plot(d: Path):
        plot_edge(r, d / "edge.png")
        return [d / "edge.png"]

    def table():
        c = _console()
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
        if p and r.mtf50_cy_per_px is not None:
            rows.insert(4, ("MTF50 (cy/m ground)", r.mtf50_cy_per_px / p))
        c.print(_kv_table(f"slanted edge: {image.name}", rows))
        sig = r.mtf_sigma if r.mtf_sigma is not None else 0 * r.mtf
        c.print(_curve_table("MTF along the edge normal", r.f_cy_per_px, {"MTF": r.mtf, "1 sigma": sig}, p))
        for w in r.warnings:
            print_warning(w, c)

    _emit(payload, as_json, out, "edge", plot, table)


def _pm(value, std) -> str:
    """``value ± std`` (4 significant digits), ``-`` for None."""
    if value is None:
        return "-"
    if std is None or not isinstance(std, float) or std != std:
        return _fmt(float(value))
    return f"{value:.4g} ± {std:.2g}"


def _target_flags(flags) -> None:
    """Quality flags of a star/bars/wedge measurement, one yellow line each."""
    for f in flags:
        _console().print(f"[yellow]flag: {f}[/]", highlight=False)


@measure_app.command()
@_handle_errors
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
    as_json: JsonOpt = False,
    out: OutOpt = None,
) -> None:
    """Siemens-star MTF per direction (ACT, ALT, diagonals). ``--center`` is in whole-image pixels."""
    from satchain.measure.star import STAR_DIRECTIONS, measure_star
    from satchain.report.measure_plots import plot_star

    check_dir_outputs(out, ["star.json", "star.png"], {"IMAGE": image})
    data, p, _ = _load(image, pixel_m)
    check_star_radius(radius, data.shape)
    region = _roi("--roi", roi)
    c = None if center is None else _numbers("--center", center, 2)
    if c is not None and region is not None:
        c = [c[0] - region[0], c[1] - region[1]]
    r = measure_star(
        data,
        cycles=cycles,
        center=c,
        radius_px=radius,
        roi=region,
        input_modulation=input_modulation,
        pixel_m=p,
        refine_center=refine_center,
    )
    payload = {"image": str(image), "roi": region, "pixel_m": p, **r.to_dict()}

    def plot(d: Path):
        plot_star(r, d / "star.png")
        return [d / "star.png"]

    def table():
        con = _console()
        ox, oy = (region[0], region[1]) if region is not None else (0, 0)
        cx, cy = r.center_xy_px[0] + ox, r.center_xy_px[1] + oy
        csd = "" if r.center_std_px is None else f" ± ({r.center_std_px[0]:.2g}, {r.center_std_px[1]:.2g})"
        rows = [
            ("cycles (checked)", r.cycles),
            (f"centre X,Y px ({r.center_from})", f"{cx:.3f}, {cy:.3f}{csd}"),
            (f"input modulation ({r.input_modulation_from})", _pm(r.input_modulation, r.input_modulation_std)),
        ]
        rows += [
            (f"MTF at Nyquist, {k}", _pm(r.mtf_at_nyquist[k], (r.mtf_at_nyquist_std or {}).get(k)))
            for k in STAR_DIRECTIONS
        ]
        con.print(_kv_table(f"Siemens star: {image.name}", rows))
        cols = {**r.mtf, "± (all)": r.mtf_all_std}
        con.print(_curve_table("MTF per direction (1-sigma of the all-angle curve)", r.f_cy_per_px, cols, p, 0.05))
        _target_flags(r.flags)

    _emit(payload, as_json, out, "star", plot, table)


@measure_app.command()
@_handle_errors
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
    as_json: JsonOpt = False,
    out: OutOpt = None,
) -> None:
    """Bar-target CTF per group (the square-wave CTF: with 3 or more groups, corrected for the finite group,
    aliased harmonics and grid phase through the target's joint MTF) and the MTF from the inverse Coltman
    series."""
    from satchain.measure.bars import measure_bars
    from satchain.report.measure_plots import plot_bars

    check_dir_outputs(out, ["bars.json", "bars.png"], {"IMAGE": image})
    data, p, _ = _load(image, pixel_m)
    periods = _numbers("--periods-px", periods_px)
    if group_roi:
        if roi is not None:
            raise ConfigError("--roi and --group-roi: give one ROI per group with --group-roi, or one --roi")
        rois = [_roi("--group-roi", g) for g in group_roi]
    elif len(periods) == 1:
        rois = [_roi("--roi", roi) or (0, 0, data.shape[-1], data.shape[0])]
    else:
        raise ConfigError(f"--periods-px = {periods_px!r}: {len(periods)} groups need one --group-roi each")
    lv = None if levels is None else tuple(_numbers("--levels", levels, 2))
    if bars_per_group == 1 or bars_per_group < 0:
        raise ConfigError(
            f"--bars-per-group = {bars_per_group}: need >= 2 bright bars per group, or 0 for a long grating"
        )
    r = measure_bars(
        data,
        periods_px=periods,
        group_rois=rois,
        direction=direction.upper(),
        levels=lv,
        pixel_m=p,
        bars_per_group=bars_per_group or None,
    )
    payload = {"image": str(image), "group_rois": rois, "pixel_m": p, **r.to_dict()}

    def plot(d: Path):
        plot_bars(r, d / "bars.png")
        return [d / "bars.png"]

    def table():
        t = Table(title=f"bar target ({r.direction}): {image.name}")
        for col in (
            "period px",
            "f cy/px",
            *(["f cy/m ground"] if p else []),
            "CTF ± 1σ",
            "of which correction",
            "MTF (Coltman inverse) ± 1σ",
            "bar phase px",
        ):
            t.add_column(col, justify="right")
        for k in range(r.f_cy_per_px.size):
            ground = [f"{r.f_cy_per_px[k] / p:.3f}"] if p else []
            mtf = None if r.mtf[k] != r.mtf[k] else float(r.mtf[k])
            t.add_row(
                f"{r.periods_px[k]:.3g}",
                f"{r.f_cy_per_px[k]:.4f}",
                *ground,
                _pm(float(r.ctf[k]), float(r.ctf_std[k])),
                "-" if r.ctf_correction is None else f"{float(r.ctf_correction[k]):+.4f}",
                _pm(mtf, float(r.mtf_std[k])),
                f"{r.phase_px[k]:.3f}",
            )
        _console().print(t)
        _console().print(
            f"large-area contrast {_pm(r.large_area_contrast, r.large_area_contrast_std)} ({r.levels_from})",
            highlight=False,
        )
        _target_flags(r.flags)

    _emit(payload, as_json, out, "bars", plot, table)


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


def _read_truth(path: Path) -> dict:
    try:
        return json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SatchainIOError(f"--truth = {str(path)!r}: no such file") from None
    except OSError as exc:
        raise SatchainIOError(f"--truth = {str(path)!r}: cannot read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise ConfigError(f"--truth = {str(path)!r}: not JSON: {exc}") from None


def _origin(text: str | None, meta: dict):
    if text is not None:
        return tuple(_numbers("--origin-m", text, 2))
    o = meta.get("origin_m")
    return None if o is None else tuple(float(v) for v in o)


def _wedge_from_truth(data, truth_path: Path, item_id: str | None, p, origin, threshold: float):
    """The wedge of a truth file, measured as ``measure auto`` does; returns (WedgeResult, summary)."""
    from satchain.measure.auto import measure_auto

    truth = _read_truth(truth_path)
    wedges = [str(it.get("id")) for it in truth.get("items", []) if it.get("kind") == "hyperbolic_wedge"]
    if item_id is None:
        if len(wedges) != 1:
            raise ConfigError(f"--id: the truth file has {len(wedges)} hyperbolic wedges {wedges}; name one")
        item_id = wedges[0]
    elif item_id not in wedges:
        raise ConfigError(f"--id = {item_id!r}: not a hyperbolic wedge of the truth file; choose from {wedges}")
    res = measure_auto(data, truth, pixel_m=p, origin_m=origin, ids=[item_id], wedge_threshold=threshold)
    found = res.by_kind("hyperbolic_wedge")
    if not found:
        raise ConfigError(f"wedge {item_id!r} not measured: {res.skipped[0]['reason']}")
    return found[0].result, found[0].summary, res.pixel_m


@measure_app.command()
@_handle_errors
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
    threshold: Annotated[float, typer.Option("--threshold", help="contrast where lines stop resolving")] = 0.15,
    truth: Annotated[Path | None, typer.Option("--truth", help="scene truth JSON: geometry from there")] = None,
    item_id: Annotated[str | None, typer.Option("--id", help="wedge id in the truth file")] = None,
    origin_m: Annotated[str | None, typer.Option("--origin-m", help="scene X,Y (m) of the image corner")] = None,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
) -> None:
    """Hyperbolic-wedge contrast scan (the paper's): resolvable line width where the contrast falls to 15 %.

    Geometry either from ``--truth`` (exact: only the rows inside the fanning stripes count), or from
    ``--line-width-start-px/--line-width-end-px`` over the ROI (which must hold the stripes only), position 0
    being the ROI's first column (ALT) or row (ACT).
    """
    from satchain.measure.wedge import measure_wedge
    from satchain.report.measure_plots import plot_wedge

    check_dir_outputs(out, ["wedge.json", "wedge.png"], {"IMAGE": image, "--truth": truth})
    data, p, meta = _load(image, pixel_m)
    if truth is not None:
        if roi is not None or line_width_start_px is not None or line_width_end_px is not None:
            raise ConfigError("--truth: the geometry comes from the truth file; drop --roi and --line-width-*")
        r, summary, p = _wedge_from_truth(data, truth, item_id, p, _origin(origin_m, meta), threshold)
        payload = {"image": str(image), "truth": str(truth), "pixel_m": p, **summary}
    else:
        if line_width_start_px is None or line_width_end_px is None:
            raise ConfigError("wedge: give --line-width-start-px and --line-width-end-px, or --truth TRUTH.json")
        region = _roi("--roi", roi) or (0, 0, data.shape[-1], data.shape[0])
        axis = region[2] - region[0] if direction.upper() == "ALT" else region[3] - region[1]
        lw = _line_widths(line_width_start_px, line_width_end_px, axis, profile)
        r = measure_wedge(
            data, line_width_px=lw, direction=direction.upper(), roi=region, threshold=threshold, pixel_m=p
        )
        payload = {"image": str(image), "roi": region, "pixel_m": p, "profile": profile, **r.to_dict()}

    def plot(d: Path):
        plot_wedge(r, d / "wedge.png", pixel_m=p)
        return [d / "wedge.png"]

    def table():
        rows = [
            ("direction (resolution)", r.direction),
            ("threshold", r.threshold),
            ("resolved line width (px)", _pm(r.resolved_line_width_px, r.resolved_line_width_px_std)),
            ("resolved line width (m)", _pm(r.resolved_line_width_m, r.resolved_line_width_m_std)),
            ("resolved frequency (cy/px)", r.resolved_f_cy_per_px),
            ("resolved frequency (cy/m ground)", r.resolved_f_cy_per_m_ground),
        ]
        _console().print(_kv_table(f"hyperbolic wedge: {image.name}", rows))
        _target_flags(r.flags)

    _emit(payload, as_json, out, "wedge", plot, table)


def _auto_plots(res, d: Path) -> list[Path]:
    from satchain.report.measure_plots import plot_bars, plot_edge, plot_star, plot_wedge

    plotters = {"slanted_edge": plot_edge, "siemens_star": plot_star, "bar_target": plot_bars}
    written = []
    for it in res.items:
        path = d / f"{it.kind}_{_safe(it.id)}.png"
        if it.kind == "hyperbolic_wedge":
            plot_wedge(it.result, path, pixel_m=res.pixel_m, title=it.id)
        else:
            plotters[it.kind](it.result, path, title=it.id)
        written.append(path)
    return written


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name)


def _auto_tables(d: dict) -> None:
    c = _console()
    t = Table(title=f"slanted edges (pixel {d['pixel_m']:g} m)")
    for col in ("id", "dir", "angle", "truth", "MTF@Nyq", "MTF50 cy/px", "RER", "H"):
        t.add_column(col, justify="right")
    for e in d["slanted_edges"]:
        t.add_row(
            e["id"],
            e["direction"],
            f"{e['angle_deg']:.3f}",
            f"{e['angle_deg_truth']:.3f}",
            _fmt(e["mtf_at_nyquist"]),
            _fmt(e["mtf50_cy_per_px"]),
            _fmt(e["rer"]),
            _fmt(e["overshoot"]),
        )
    c.print(t)
    for s in d["siemens_star"]:
        rows = [(f"MTF at Nyquist, {k}", v) for k, v in s["mtf_at_nyquist"].items()]
        c.print(_kv_table(f"Siemens star {s['id']} ({s['cycles']} cycles)", rows))
    for b in d["bar_targets"]:
        rows = [
            (
                f"period {g['period_m']:g} m ({g['period_px']:.3g} px): CTF, MTF",
                f"{g['ctf']:.4f}, {g['mtf']:.4f}",
            )
            for g in b["groups"]
        ]
        c.print(_kv_table(f"bar target {b['id']} ({b['direction']})", rows))
    for w in d["hyperbolic_wedge"]:
        rows = [
            ("resolution (line width, m)", w["resolution_m"]),
            ("frequency (cy/px)", w["resolved_f_cy_per_px"]),
        ]
        c.print(_kv_table(f"hyperbolic wedge {w['id']} ({w['direction']}, threshold {w['threshold']:.0%})", rows))
    if d["skipped"]:
        t = Table(title="not measured")
        for col in ("id", "kind", "reason"):
            t.add_column(col)
        for s in d["skipped"]:
            t.add_row(s["id"], s["kind"], s["reason"])
        c.print(t)
    for w in d.get("warnings", []):
        print_warning(w, c)


@measure_app.command()
@_handle_errors
def auto(
    image: ImageArg,
    truth: Annotated[Path, typer.Option("--truth", help="the scene's truth JSON (written with the render)")],
    origin_m: Annotated[
        str | None, typer.Option("--origin-m", help="scene X,Y (m) of the image's top-left corner")
    ] = None,
    threshold: Annotated[float, typer.Option("--threshold", help="wedge contrast threshold")] = 0.15,
    pixel_m: PixelOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
) -> None:
    """Every applicable measurement of a (simulated) image, guided by its scene's truth file."""
    from satchain.measure.auto import measure_auto

    check_dir_outputs(out, ["auto.json", "*.png"], {"IMAGE": image, "--truth": truth})
    data, p, meta = _load(image, pixel_m)
    res = measure_auto(data, _read_truth(truth), pixel_m=p, origin_m=_origin(origin_m, meta), wedge_threshold=threshold)
    payload = {"image": str(image), "truth": str(truth), **res.to_dict()}
    _emit(payload, as_json, out, "auto", lambda d: _auto_plots(res, d), lambda: _auto_tables(payload))
    if not res.items:  # a run that measured nothing is not a success (exit status 2, the reasons on stderr)
        from satchain._safety import nothing_measured

        raise nothing_measured(res.skipped, data, p, truth)


from satchain import cli_find as _cli_find  # noqa: E402,F401  (registers `measure find`)
