"""``satchain measure auto``: every target of a (simulated) image, guided by its scene's truth file.

Registered on the ``measure`` sub-app in :mod:`satchain.cli.measure`.
"""

from __future__ import annotations

from pathlib import Path

from rich.table import Table

from satchain._safety import check_dir_outputs
from satchain.cli._common import handle_errors, print_warning
from satchain.cli.options import (
    BandOpt,
    FullScaleOpt,
    ImageArg,
    JsonOpt,
    OriginOpt,
    OutOpt,
    PixelOpt,
    ThresholdOpt,
    TruthRequiredOpt,
    ground_fields,
    load_image,
    parse_full_scale,
    parse_origin,
    read_truth,
)
from satchain.cli.output import emit, fmt, kv_table, print_ground, wide_console

__all__ = ["auto"]


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name)


def _auto_plots(res, d: Path) -> list[Path]:
    from satchain.report.kinds import REPORT_KINDS

    written = []
    for it in res.items:
        path = d / f"{it.kind}_{_safe(it.id)}.png"
        REPORT_KINDS[it.kind].plot(it.result, path, title=it.id, pixel_m=res.pixel_m)
        written.append(path)
    return written


def _edges_table(d: dict) -> Table:
    from satchain.report.kinds import EDGES

    t = Table(title=f"slanted edges (pixel {d['pixel_m']:g} m)")
    for col in ("id", "dir", "angle", "truth", "MTF@Nyq", "MTF50 cy/px", "MTF50 cy/m", "RER", "H"):
        t.add_column(col, justify="right")
    for e in d[EDGES.key]:
        t.add_row(
            e["id"],
            e["direction"],
            f"{e['angle_deg']:.3f}",
            f"{e['angle_deg_truth']:.3f}",
            fmt(e["mtf_at_nyquist"]),
            fmt(e["mtf50_cy_per_px"]),
            fmt(None if e["mtf50_cy_per_px"] is None else e["mtf50_cy_per_px"] / d["pixel_m"]),
            fmt(e["rer"]),
            fmt(e["overshoot"]),
        )
    return t


def _auto_tables(d: dict) -> None:
    from satchain.report.kinds import BARS, STARS, WEDGES

    c = wide_console()
    c.print(_edges_table(d))
    for s in d[STARS.key]:
        rows = [(f"MTF at Nyquist, {k}", v) for k, v in s["mtf_at_nyquist"].items()]
        c.print(kv_table(f"Siemens star {s['id']} ({s['cycles']} cycles)", rows))
    for b in d[BARS.key]:
        rows = [
            (f"period {g['period_m']:g} m ({g['period_px']:.3g} px): CTF, MTF", f"{g['ctf']:.4f}, {g['mtf']:.4f}")
            for g in b["groups"]
        ]
        c.print(kv_table(f"bar target {b['id']} ({b['direction']})", rows))
    for w in d[WEDGES.key]:
        rows = [
            ("resolution (line width, m)", w["resolution_m"]),
            ("frequency (cy/px)", w["resolved_f_cy_per_px"]),
            ("frequency (cy/m ground)", w["resolved_f_cy_per_m_ground"]),
        ]
        c.print(kv_table(f"hyperbolic wedge {w['id']} ({w['direction']}, threshold {w['threshold']:.0%})", rows))
    print_ground(d["pixel_m"])
    if d["skipped"]:
        t = Table(title="not measured")
        for col in ("id", "kind", "reason"):
            t.add_column(col)
        for s in d["skipped"]:
            t.add_row(s["id"], s["kind"], s["reason"])
        c.print(t)
    for w in d.get("warnings", []):
        print_warning(w, c)


@handle_errors
def auto(
    image: ImageArg,
    truth: TruthRequiredOpt,
    origin_m: OriginOpt = None,
    threshold: ThresholdOpt = 0.15,
    pixel_m: PixelOpt = None,
    band: BandOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
    full_scale: FullScaleOpt = None,
) -> None:
    """Every applicable measurement of a (simulated) image, guided by its scene's truth file."""
    from satchain.measure.auto import measure_auto

    check_dir_outputs(out, ["auto.json", "*.png"], {"IMAGE": image, "--truth": truth})
    data, p, meta = load_image(image, pixel_m, band)
    truth_dict = read_truth(truth)  # read before --origin-m is parsed (the order of the checks is kept)
    origin = parse_origin(origin_m, meta)
    fs = parse_full_scale(full_scale, data, meta)
    res = measure_auto(data, truth_dict, pixel_m=p, origin_m=origin, wedge_threshold=threshold, full_scale=fs)
    payload = {"image": str(image), "truth": str(truth), **ground_fields(res.pixel_m, meta), **res.to_dict()}
    emit(payload, as_json, out, "auto", lambda d: _auto_plots(res, d), lambda: _auto_tables(payload))
    if not res.items:  # a run that measured nothing is not a success (exit status 2, the reasons on stderr)
        from satchain._safety import nothing_measured

        raise nothing_measured(res.skipped, data, p, truth)
