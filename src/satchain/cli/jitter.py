"""``satchain measure jitter``: line-of-sight motion from a long straight near-vertical edge of a pushbroom image.

Registered on the ``measure`` sub-app by :mod:`satchain.cli.measure`; the shared options come from
:mod:`satchain.cli.options`, the printing and writing from :mod:`satchain.cli.output`.
"""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table

from satchain._safety import check_dir_outputs
from satchain.cli._common import handle_errors, print_warning
from satchain.cli.options import (
    BandOpt,
    FullScaleOpt,
    ImageArg,
    JsonOpt,
    NodataOpt,
    OutOpt,
    PixelOpt,
    RoiOpt,
    ground_fields,
    load_image,
    measuring,
    parse_full_scale,
    parse_roi,
    parse_valid,
)
from satchain.cli.output import emit, kv_table, one_plot, print_ground, wide_console

__all__ = ["jitter"]


def _jitter_tables(r, name: str, p: float | None, note: str | None = None) -> None:
    c = wide_console()
    rows = [
        ("edge angle (deg from y/ALT)", r.angle_deg),
        ("line time (s)", r.line_time_s),
        ("line-rate Nyquist (Hz)", r.nyquist_hz),
        ("lines measured", f"{r.n_lines_used} of {len(r.lines)}"),
        ("position noise, 1 sigma (px)", r.position_noise_px),
        ("rms of detrended positions (px)", f"{r.rms_px:.4g} (motion alone {r.rms_motion_px:.4g})"),
        ("line-to-line rms (px)", f"{r.line_to_line_rms_px:.4g} (motion alone {r.line_to_line_motion_rms_px:.4g})"),
        ("residual rms after the peaks (px)", r.residual_rms_px),
        (f"detection limit (px, false alarm {r.false_alarm:g})", r.detection_limit_px),
        ("quality flags", ", ".join(r.flags) if r.flags else "none"),
    ]
    c.print(kv_table(f"line-of-sight motion from an edge: {name}", rows))
    print_ground(p, note)
    t = Table(title="significant sinusoids: x(t) = A sin(2 pi f t + phase), t = line x line time (1 sigma)")
    for col in ("f (Hz)", "A (px)", *(["A (m ground)"] if p else []), "phase (deg)", "cycles", "false alarm", "flags"):
        t.add_column(col, justify="right")
    for k in r.peaks:
        t.add_row(
            f"{k.frequency_hz:.6g} ± {k.frequency_sigma_hz:.2g}",
            f"{k.amplitude_px:.4g} ± {k.amplitude_sigma_px:.2g}",
            *([f"{k.amplitude_px * p:.4g}"] if p else []),
            f"{k.phase_deg:.1f} ± {k.phase_sigma_deg:.2g}",
            f"{k.cycles:.3g}",
            f"{k.false_alarm_probability:.2g}",
            ", ".join(k.flags) or "-",
        )
    c.print(t)
    for w in r.warnings:
        print_warning(w, c)


@handle_errors
def jitter(
    image: ImageArg,
    line_time: Annotated[float, typer.Option("--line-time", help="time between consecutive image lines (s)")],
    roi: RoiOpt = None,
    max_peaks: Annotated[int, typer.Option("--max-peaks", help="most sinusoids fitted (1-10)")] = 3,
    false_alarm: Annotated[
        float,
        typer.Option("--false-alarm", help="false-alarm probability a reported peak must beat (0-0.5)"),
    ] = 1e-3,
    pixel_m: PixelOpt = None,
    band: BandOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
    full_scale: FullScaleOpt = None,
    nodata: NodataOpt = None,
) -> None:
    """Line-of-sight motion from a long straight near-vertical (ACT) edge: frequencies, amplitudes and phases.

    Each image line's crossing of the edge (as ``measure edge --json``'s ``edge_position_px``) less the edge's
    tilt; the significant sinusoids (generalised Lomb-Scargle periodogram, Baluev false-alarm probability,
    joint least-squares fit), each with its 1-sigma, the rms and line-to-line rms of the positions.  Line
    ``i`` is at ``t = i x --line-time``; frequencies above the line-rate Nyquist ``1 / (2 line time)`` appear
    folded (aliased).  ``-o DIR`` writes jitter.json and jitter.png.
    """
    from satchain.measure.jitter import check_line_time, measure_jitter
    from satchain.report.measure_plots import plot_jitter

    check_dir_outputs(out, ["jitter.json", "jitter.png"], {"IMAGE": image})
    from satchain._validate import check_range

    check_line_time("--line-time", line_time)
    check_range("--max-peaks", max_peaks, 1, 10)
    check_range("--false-alarm", false_alarm, 0.0, 0.5, lo_open=True, hi_open=True)
    data, p, meta = load_image(image, pixel_m, band)
    region = parse_roi("--roi", roi)
    fs = parse_full_scale(full_scale, data, meta)
    valid = parse_valid(data, nodata, meta, image)
    with measuring(image, valid):
        r = measure_jitter(
            data, line_time_s=line_time, roi=region, max_peaks=max_peaks, false_alarm=false_alarm,
            valid=valid, full_scale=fs,
        )  # fmt: skip
    ground = ground_fields(p, meta)
    payload = {"image": str(image), "roi": region, **ground, **r.to_dict()}
    emit(
        payload, as_json, out, "jitter", lambda d: one_plot(plot_jitter, r, d / "jitter.png"),
        lambda: _jitter_tables(r, image.name, p, ground.get("pixel_m_note")),
    )  # fmt: skip
