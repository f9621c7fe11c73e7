"""``satchain budget``: the predicted MTF/CTF budget and derived quantities of a system, as tables or JSON
(:func:`satchain.prediction.budget.budget_results`); ``-o DIR`` also writes CSV tables, JSON and plots.

Registered on the app by :mod:`satchain.cli.main`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from satchain._safety import check_dir_outputs, check_run_dir
from satchain.cli._common import console, handle_errors, parse_numbers, system_from_options
from satchain.cli.options import PresetOpt, SystemOpt

__all__ = ["budget"]


def _parse_floats(name: str, text: str | None) -> list[float] | None:
    return None if text is None else parse_numbers(name, text, minimum=0.0)


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return ", ".join(_fmt(x) for x in v)
    return str(v)


def _print_budget(res: dict[str, Any]) -> None:
    t = Table(title=f"{res['system']}: derived quantities", show_header=True)
    t.add_column("quantity")
    t.add_column("value")
    for k, v in res["derived"].items():
        t.add_row(k, _fmt(v))
    console.print(t)
    for d in ("alt", "act"):
        name = "ALT (along-track, f_y)" if d == "alt" else "ACT (across-track, f_x)"
        comps = list(res["mtf"][d])
        # the detector pixel's axis (an image with a line-rate error or Earth rotation has its rows alt_scale px
        # apart: motion_geometry; `run` predicts on the image's axis); motion terms are signed expected OTFs
        t = Table(title=f"MTF and CTF budget, {name}; f on the detector pixel's axis, motion terms signed")
        for c in ["f cy/mm", "f cy/det px", "f cy/m gnd", *comps, "CTF Coltman", "CTF paper"]:
            t.add_column(c, justify="right")
        cols = [
            res["frequencies_cy_per_mm"],
            res["frequencies_cy_per_px"][d],
            res["frequencies_cy_per_m_ground"][d],
            *[res["mtf"][d][c] for c in comps],
            res["ctf"][d]["coltman"],
            res["ctf"][d]["fourier_synthesis"],
        ]
        for row in zip(*cols, strict=True):
            t.add_row(*[f"{v:.4f}" for v in row])
        console.print(t)
    ny = res["mtf_at_nyquist"]
    console.print(
        f"MTF at Nyquist: ALT {ny['alt']:.4f}, ACT {ny['act']:.4f}   "
        f"MTFA (0..Nyquist, cy/px): ALT {res['mtfa']['alt']:.4f}, ACT {res['mtfa']['act']:.4f}"
    )
    if "motion_geometry" in res:
        _print_motion_geometry(res["motion_geometry"])
    for key in ("radiometry", "quality"):
        if key in res:
            console.print(
                f"[bold]{key}[/]: "
                + ", ".join(f"{k}={_fmt(v)}" for k, v in res[key].items() if not isinstance(v, (list, dict)))
            )
    if res.get("bands"):
        _print_bands(res["bands"])
    if "cfa" in res:
        _print_cfa(res["cfa"])
    if "staggered" in res:
        st = res["staggered"]
        ny_st, one, comb = st["nyquist_cy_per_mm"], st["mtf_at_single_nyquist"], st["mtf_at_combined_nyquist"]
        console.print(
            f"staggered: two arrays combined onto {st['combined_pitch_m'] * 1e6:.3g} um "
            f"({st['combined_gsd_m']['act']:.4g} m GSD); Nyquist {ny_st['axis']:.2f} cy/mm along the axes "
            f"({ny_st['diagonal']:.2f} diagonally, one array {ny_st['single_array']:.2f}); MTF after the "
            f"combination at the combined Nyquist ALT {comb['alt']:.4f}, "
            f"ACT {comb['act']:.4f}, at one array's Nyquist ALT {one['alt']:.4f}, ACT {one['act']:.4f}",
            markup=False,
            highlight=False,
        )


def _print_bands(bands: list[dict[str, Any]]) -> None:
    """One row per ``[[bands]]`` entry: its own GSD, Nyquist, MTF there, signal, SNR, NIIRS and offset from PAN."""
    ref = bands[0]["registration"]["reference_band"]
    t = Table(title=f"bands: each at its own pixel, Nyquist and radiometry; offsets from {ref!r} in the band's px")
    heads = ["band", "centre nm", "GSD m", "Nyquist cy/mm", "MTF@Ny ACT", "MTF@Ny ALT", "signal e-", "SNR", "NIIRS",
             "delay ms", "offset ALT px", "offset ACT px",
             "motion px (oscillation amplitude; Earth; line rate)"]  # fmt: skip
    for c in heads:
        t.add_column(c, justify="left" if c == "band" else "right")
    for b in bands:
        reg = b["registration"]
        osc = ", ".join(f"{o['axis']} {o['amplitude_px']:.3f} @ {o['frequency_hz']:g} Hz" for o in reg["oscillations"])
        if reg.get("earth_rotation"):
            e = reg["earth_rotation"]
            osc += f"{', ' if osc else ''}Earth ALT {e['alt_px']:+.3f} ACT {e['act_px']:+.3f}"
        if reg.get("line_rate"):
            e = reg["line_rate"]
            osc += f"{', ' if osc else ''}line rate ALT {e['alt_px']:+.3f} ACT {e['act_px']:+.3f}"
        t.add_row(
            b["name"],
            f"{b['center_wavelength_m'] * 1e9:.1f}",
            f"{b['gsd_m']:.4g}",
            f"{b['nyquist_cy_per_mm']['alt']:.4g}",
            f"{b['mtf_at_nyquist']['act']:.4f}",
            f"{b['mtf_at_nyquist']['alt']:.4f}",
            f"{b['signal_e']:.5g}",
            f"{b['snr']:.4g}",
            "-" if b["niirs"] is None else f"{b['niirs']:.3f}",
            f"{reg['delay_s'] * 1e3:.2f}",
            f"{reg['static_px']['alt']:+.3f}",
            f"{reg['static_px']['act']:+.3f}",
            osc or "-",
        )
    console.print(t)


def _print_cfa(cfa: dict[str, Any]) -> None:
    """A colour filter array's planes side by side (one column each): sampling, Nyquist, MTF there and where each
    aliases."""
    planes = cfa["planes"]
    t = Table(title=f"colour filter array {cfa['pattern']}: each colour plane on its own grid (f in cy/px)")
    t.add_column("quantity")
    for colour in planes:
        t.add_column(colour, justify="right")

    def row(name: str, fmt: str, get) -> None:
        t.add_row(name, *(format(get(p), fmt) for p in planes.values()))

    t.add_row("sampling", *("2 px grid" if p["lattice_pitch_px"] == 2.0 else "quincunx" for p in planes.values()))
    row("effective wavelength (nm)", ".1f", lambda p: p["effective_wavelength_m"] * 1e9)
    for d, name in (("act", "ACT"), ("alt", "ALT"), ("diagonal", "diagonal")):
        row(f"Nyquist {name}", ".4f", lambda p, d=d: p["nyquist_cy_per_px"][d])
        row(f"MTF at Nyquist {name}", ".4f", lambda p, d=d: p["mtf_at_nyquist"][d])
    row("grid Nyquist (edge on the plane's grid)", ".4f", lambda p: p["grid_nyquist_cy_per_px"])
    row("MTF at grid Nyquist ACT", ".4f", lambda p: p["mtf_at_grid_nyquist"]["act"])
    row("MTF at grid Nyquist ALT", ".4f", lambda p: p["mtf_at_grid_nyquist"]["alt"])
    for d, name in (("act", "ACT"), ("alt", "ALT"), ("diagonal", "diagonal")):
        row(f"aliases to 0 at, {name}", ".4f", lambda p, d=d: p["alias_cy_per_px"][d])
    row("MTF volume beyond Nyquist", ".3f", lambda p: p["aliased_fraction"])
    console.print(t)
    sources = sorted(set(cfa["responses"].values()))
    console.print("colour responses: " + "; ".join(
        f"{', '.join(c for c, s in cfa['responses'].items() if s == src)}: {src}" for src in sources),
        markup=False, highlight=False)  # fmt: skip


def _print_motion_geometry(g: dict[str, Any]) -> None:
    """The pushbroom motion's geometry (satchain.tf.pushbroom): one row per quantity, nested ones flattened."""
    t = Table(title="pushbroom motion geometry (TDI window, line displacement, Earth rotation)")
    t.add_column("quantity")
    t.add_column("value")

    def rows(prefix: str, v: Any) -> None:
        if isinstance(v, dict):
            for k, item in v.items():
                rows(f"{prefix}.{k}" if prefix else k, item)
        elif isinstance(v, list):
            for i, item in enumerate(v):
                rows(f"{prefix}[{i}]", item)
        else:
            t.add_row(prefix, _fmt(v))

    rows("", g)
    console.print(t)


def _budget(system_obj, freqs: list[float] | None) -> dict[str, Any]:
    from satchain.prediction.budget import budget_results

    return budget_results(system_obj, freqs)


@handle_errors
def budget(
    preset: PresetOpt = None,
    system: SystemOpt = None,
    freqs: Annotated[
        str | None, typer.Option("--freqs", help="focal-plane frequencies in cy/mm, e.g. 10,42.5,85")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of tables")] = False,
    out: Annotated[Path | None, typer.Option("-o", "--out", help="also write CSV tables, JSON and plots here")] = None,
) -> None:
    """Predicted MTF/CTF budget, derived quantities (GSD, Nyquist, Q, ...) of a system."""
    check_dir_outputs(out, ["*.json", "*.csv", "*.png"], {"--system": system})
    if out is not None:
        check_run_dir(out, kind="budget")  # a user's folder (their budget.json) is refused, never overwritten
    s = system_from_options(preset, system)
    res = _budget(s, _parse_floats("--freqs", freqs))
    if out is not None:
        from satchain._safety import write_run_marker
        from satchain.report.budget import write_budget_outputs

        out.mkdir(parents=True, exist_ok=True)
        write_run_marker(out, kind="budget")  # satchain's own: a later budget -o may write here again
        written = write_budget_outputs(s, res, out)
        if not as_json:
            console.print("wrote " + ", ".join(str(p) for p in written), markup=False, highlight=False)
    if as_json:
        print(json.dumps(res, indent=2))
    else:
        _print_budget(res)
