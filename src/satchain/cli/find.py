"""``satchain measure find IMAGE``: ACT and ALT MTF from the slanted edges found in an image (no truth file).

Registered on the ``measure`` sub-app in :mod:`satchain.cli.measure`.  Prints a table of
the edges used, the combined MTF at Nyquist with its 1-sigma, the CEOS-style table (MTF at f / f_s = 0, 0.02,
..., 0.5 and 0.25; with a ground pixel size, also in cy/m), flags and the rejected segments counted by reason;
``--json`` prints JSON, ``--csv`` the CEOS table as CSV; ``-o DIR`` writes ``find.json``, ``find_ceos.csv`` and
``find.png`` there (atomically).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from satchain.cli._common import handle_errors
from satchain.cli.options import (
    BandOpt,
    FrequencyAxisOpt,
    FullScaleOpt,
    ImageArg,
    JsonOpt,
    NodataOpt,
    OutOpt,
    PixelOpt,
    ground_fields,
    load_image,
    measuring,
    parse_frequency_axis,
    parse_full_scale,
    parse_valid,
)
from satchain.cli.output import emit, fmt, print_ground, wide_console

__all__ = ["find"]


def _edges_table(res, name: str) -> Table:
    t = Table(title=f"slanted edges found: {name}")
    ground = ["MTF50 cy/m"] if res.pixel_m else []
    for col in ("#", "dir", "centre x,y", "ROI", "angle", "length", "CNR", "MTF@Nyq", "+-1s", "MTF50", *ground):
        t.add_column(col, justify="right")
    for k, e in enumerate(res.edges):
        c = e.candidate
        t.add_row(
            str(k),
            e.direction,
            f"{c.center_xy[0]:.0f},{c.center_xy[1]:.0f}",
            ",".join(map(str, c.roi)),
            f"{e.angle_deg:.2f}",
            f"{c.length_px:.0f}",
            f"{c.cnr:.0f}",
            f"{e.mtf_at_nyquist:.4f}",
            f"{e.mtf_at_nyquist_sigma:.4f}",
            fmt(e.mtf50_cy_per_px),
            *([fmt(e.mtf50_cy_per_m_ground)] if res.pixel_m else []),
        )
    return t


def _combined_table(res, pixel_m) -> Table:
    t = Table(title="combined MTF (inverse-variance mean of the edges)")
    for col in (
        "direction",
        "edges",
        "MTF@Nyquist",
        "+-1 sigma",
        "scatter",
        "chi2/dof",
        "MTF50 cy/px",
        *(["MTF50 cy/m"] if pixel_m else []),
    ):
        t.add_column(col, justify="right")
    for d, c in res.combined.items():
        m50 = c.mtf50_cy_per_px
        t.add_row(
            d,
            str(c.n_edges),
            f"{c.mtf_at_nyquist:.4f}",
            f"{c.mtf_at_nyquist_sigma:.4f}",
            fmt(c.scatter_at_nyquist),
            fmt(c.chi2_reduced_at_nyquist),
            fmt(m50),
            *([fmt(None if m50 is None else m50 / pixel_m)] if pixel_m else []),
        )
    return t


def _ceos_rich(tab: dict, axis: str) -> Table:
    where = "the edge normal" if axis == "normal" else "the image row (ACT) / column (ALT), MTF_Estimator's axis"
    t = Table(title=f"CEOS-style MTF at f / f_s (f_s = 1 cy/px; 0.5 = Nyquist), along {where}")
    ground = "f_cy_per_m_ground" in tab
    for col in ("f/fs", *(["f cy/m"] if ground else []), "ACT", "+-1s", "ALT", "+-1s"):
        t.add_column(col, justify="right")
    for i in range(tab["f_over_fs"].size):
        cells = [tab[k][i] for k in ("mtf_act", "mtf_act_sigma", "mtf_alt", "mtf_alt_sigma")]
        g = [f"{tab['f_cy_per_m_ground'][i]:.4g}"] if ground else []
        t.add_row(f"{tab['f_over_fs'][i]:.2f}", *g, *("-" if v != v else f"{v:.4f}" for v in cells))
    return t


def _axis_note(res) -> str | None:
    """The row axis's factor per edge (``f_row = cos(tilt) f_normal``), or None on the normal axis."""
    if res.frequency_axis == "normal":
        return None
    scales = ", ".join(f"{k}: {e.frequency_scale:.4f}" for k, e in enumerate(res.edges))
    return (f"frequency axis: image row (ACT) / column (ALT), MTF_Estimator's convention: f_row = cos(tilt) x "
            f"f_normal, per edge {scales}")  # fmt: skip


@handle_errors
def find(
    image: ImageArg,
    pixel_m: PixelOpt = None,
    band: BandOpt = None,
    min_length: Annotated[float, typer.Option("--min-length", help="shortest usable edge (px)")] = 25.0,
    max_edges: Annotated[
        int, typer.Option("--max-edges", help="measure at most N edges (the longest, ACT and ALT in turn)")
    ] = 200,
    min_cnr: Annotated[float, typer.Option("--min-cnr", help="smallest edge contrast / pixel noise")] = 10.0,
    f_max: Annotated[
        float, typer.Option("--f-max", help="last f/f_s of the CEOS table: 0.5 (Nyquist) up to 1.0")
    ] = 0.5,
    as_csv: Annotated[bool, typer.Option("--csv", help="print the CEOS table as CSV")] = False,
    as_json: JsonOpt = False,
    out: OutOpt = None,
    full_scale: FullScaleOpt = None,
    nodata: NodataOpt = None,
    frequency_axis: FrequencyAxisOpt = "normal",
) -> None:
    """ACT and ALT MTF (with 1-sigma) from every usable slanted edge found automatically (no truth file).

    With a metric pixel size (``--pixel-m`` or the raster's projected transform) the edges, the combined
    curves and the CEOS table also give cy/m on the ground.  ``--frequency-axis row``: MTF_Estimator's axis
    (along the image row / column, ``f_row = cos(tilt) f_normal`` per edge, printed).
    """
    from satchain._validate import check_positive, check_range
    from satchain.measure._common import to_jsonable
    from satchain.measure.find_mtf import ceos_csv, ceos_table, measure_found_edges
    from satchain.report.find_plots import plot_find

    check_range("--f-max", f_max, 0.02, 1.0)
    check_range("--min-length", min_length, 12, None)
    check_range("--max-edges", max_edges, 1, None)
    check_positive("--min-cnr", min_cnr)
    axis = parse_frequency_axis(frequency_axis)
    data, p, meta = load_image(image, pixel_m, band)
    fs = parse_full_scale(full_scale, data, meta)
    valid = parse_valid(data, nodata, meta, image)
    with measuring(image, valid):
        res = measure_found_edges(
            data, pixel_m=p, min_length_px=min_length, max_edges=max_edges, min_cnr=min_cnr, full_scale=fs,
            valid=valid, frequency_axis=axis,
        )  # fmt: skip
    csv_text = ceos_csv(res, f_max=f_max, pixel_m=p)
    tab = ceos_table(res, f_max=f_max, pixel_m=p)
    payload = {"image": str(image), **ground_fields(p, meta), **res.to_dict(), "ceos_csv": csv_text,
               "ceos_table": to_jsonable(tab)}  # fmt: skip

    def plot(d: Path):
        from satchain.report._save import write_text

        write_text(d / "find_ceos.csv", csv_text)
        plot_find(res, d / "find.png", image=data, title=image.name)
        return [d / "find_ceos.csv", d / "find.png"]

    def table():
        c = wide_console()
        if as_csv:
            print(csv_text, end="")
            return
        c.print(_edges_table(res, image.name))
        c.print(_combined_table(res, p))
        c.print(_ceos_rich(tab, res.frequency_axis))
        print_ground(p, payload.get("pixel_m_note"))
        if (note := _axis_note(res)) is not None:
            c.print(note, highlight=False, markup=False)
        for f in [*res.flags, *(fl for cm in res.combined.values() for fl in cm.flags)]:
            c.print(f"[yellow]flag:[/] {f}", highlight=False)
        for k, e in enumerate(res.edges):
            for w in e.warnings:
                c.print(f"[yellow]edge {k}:[/] {w}", highlight=False)
        counts = payload["rejection_counts"]
        if counts:
            c.print("rejected segments: " + ", ".join(f"{k} {v}" for k, v in counts.items()), highlight=False)

    emit(payload, as_json, out, "find", plot, table)
