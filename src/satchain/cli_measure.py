"""``satchain measure``: image-quality measurements from image files (a typer sub-app, mounted by cli.py).

Commands: ``edge``, ``star``, ``bars``, ``wedge`` (one target in a region) and ``auto`` (every target of a scene,
from its truth file).  Images: TIFF (float or integer), PNG (8/16-bit) and NPY, read by
:func:`satchain.io.read_image`; the ground pixel size comes from ``--pixel-m`` or the file's metadata.
Regions are ``X0,Y0,X1,Y1`` in pixels (x = column, y = row), half-open.  ``--json`` prints the result as JSON;
``-o DIR`` writes ``<command>.json`` and a figure there.  Bad input: one line on stderr, exit status 2.
"""

from __future__ import annotations

import functools
import json
import math
import shutil
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from satchain.errors import ConfigError, SatchainError, SatchainIOError

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


def _handle_errors(fn):
    """satchain's errors -> one clear line on stderr and exit status 2 (no traceback)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except SatchainError as exc:
            Console(stderr=True).print(f"[bold red]error:[/] {exc}", highlight=False)
            raise typer.Exit(2) from None

    return wrapper


def _numbers(name: str, text: str, n: int | None = None) -> list[float]:
    """Comma-separated finite numbers (exactly ``n`` when given)."""
    try:
        vals = [float(t) for t in str(text).replace(" ", "").split(",") if t != ""]
    except ValueError:
        vals = []
    if not vals or (n is not None and len(vals) != n) or not all(math.isfinite(v) for v in vals):
        what = f"{n} comma-separated numbers" if n else "comma-separated numbers"
        raise ConfigError(f"{name} = {text!r}: must be {what}")
    return vals


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
) -> None:
    """Slanted-edge MTF (ISO 12233 e-SFR, improved): MTF, MTF at Nyquist, MTF50, RER, overshoot."""
    from satchain.measure.edge import measure_edge
    from satchain.report.measure_plots import plot_edge

    data, p, _ = _load(image, pixel_m)
    region = _roi("--roi", roi)
    r = measure_edge(data, roi=region, pixel_m=p)
    payload = {"image": str(image), "roi": region, "pixel_m": p, **r.to_dict()}

    def plot(d: Path):
        plot_edge(r, d / "edge.png")
        return [d / "edge.png"]

    def table():
        c = _console()
        rows = [
            ("edge angle (deg from y/ALT)", r.angle_deg),
            ("MTF direction", r.direction),
            ("MTF at Nyquist", r.mtf_at_nyquist),
            ("  predicted noise (1 sigma)", r.mtf_at_nyquist_std),
            ("MTF50 (cy/px)", r.mtf50_cy_per_px),
            ("RER", r.rer),
            ("overshoot H", r.overshoot),
            ("edge contrast", r.contrast),
            ("noise sigma", r.noise_sigma),
            ("lines used", r.n_lines),
        ]
        if p and r.mtf50_cy_per_px is not None:
            rows.insert(5, ("MTF50 (cy/m ground)", r.mtf50_cy_per_px / p))
        c.print(_kv_table(f"slanted edge: {image.name}", rows))
        c.print(_curve_table("MTF along the edge normal", r.f_cy_per_px, {"MTF": r.mtf}, p))
        for w in r.warnings:
            c.print(f"[yellow]warning:[/] {w}", highlight=False)

    _emit(payload, as_json, out, "edge", plot, table)


@measure_app.command()
@_handle_errors
def star(
    image: ImageArg,
    cycles: Annotated[int, typer.Option("--cycles", help="periods per revolution of the sinusoidal star")],
    center: Annotated[str | None, typer.Option("--center", help="star centre X,Y in image pixels")] = None,
    radius: Annotated[float | None, typer.Option("--radius", help="outer radius used (px)")] = None,
    input_modulation: Annotated[
        float | None, typer.Option("--input-modulation", help="the star's own modulation; default: outer radii")
    ] = None,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
) -> None:
    """Siemens-star MTF per direction (ACT, ALT, diagonals). ``--center`` is in whole-image pixels."""
    from satchain.measure.star import STAR_DIRECTIONS, measure_star
    from satchain.report.measure_plots import plot_star

    data, p, _ = _load(image, pixel_m)
    region = _roi("--roi", roi)
    c = None if center is None else _numbers("--center", center, 2)
    if c is not None and region is not None:
        c = [c[0] - region[0], c[1] - region[1]]
    r = measure_star(
        data, cycles=cycles, center=c, radius_px=radius, roi=region, input_modulation=input_modulation, pixel_m=p
    )
    payload = {"image": str(image), "roi": region, "pixel_m": p, **r.to_dict()}

    def plot(d: Path):
        plot_star(r, d / "star.png")
        return [d / "star.png"]

    def table():
        con = _console()
        rows = [("cycles", r.cycles), ("input modulation", r.input_modulation)]
        rows += [(f"MTF at Nyquist, {k}", r.mtf_at_nyquist[k]) for k in STAR_DIRECTIONS]
        con.print(_kv_table(f"Siemens star: {image.name}", rows))
        con.print(_curve_table("MTF per direction", r.f_cy_per_px, r.mtf, p, step=0.05))

    _emit(payload, as_json, out, "star", plot, table)


@measure_app.command()
@_handle_errors
def bars(
    image: ImageArg,
    periods_px: Annotated[str, typer.Option("--periods-px", help="period of each group (px), P1,P2,...")],
    group_roi: Annotated[
        list[str] | None, typer.Option("--group-roi", help="X0,Y0,X1,Y1 of one group (repeat, one per period)")
    ] = None,
    direction: Annotated[str, typer.Option("--direction", help="ACT: bars along y; ALT: bars along x")] = "ACT",
    levels: Annotated[
        str | None, typer.Option("--levels", help="large-area DARK,BRIGHT levels; default: the widest group")
    ] = None,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
) -> None:
    """Bar-target CTF per group and the MTF from the inverse Coltman series."""
    from satchain.measure.bars import measure_bars
    from satchain.report.measure_plots import plot_bars

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
    r = measure_bars(data, periods_px=periods, group_rois=rois, direction=direction.upper(), levels=lv, pixel_m=p)
    payload = {"image": str(image), "group_rois": rois, "pixel_m": p, **r.to_dict()}

    def plot(d: Path):
        plot_bars(r, d / "bars.png")
        return [d / "bars.png"]

    def table():
        t = Table(title=f"bar target ({r.direction}): {image.name}")
        for col in ("period px", "f cy/px", *(["f cy/m ground"] if p else []), "CTF", "MTF (Coltman inverse)"):
            t.add_column(col, justify="right")
        for k in range(r.f_cy_per_px.size):
            ground = [f"{r.f_cy_per_px[k] / p:.3f}"] if p else []
            t.add_row(f"{r.periods_px[k]:.3g}", f"{r.f_cy_per_px[k]:.4f}", *ground, f"{r.ctf[k]:.4f}", f"{r.mtf[k]:.4f}")
        _console().print(t)

    _emit(payload, as_json, out, "bars", plot, table)
