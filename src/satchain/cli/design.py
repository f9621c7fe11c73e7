"""``satchain design``: the inverse question by the budget, which values of a system key meet every target
(:func:`satchain.studies.design.design`). Registered on the app by :mod:`satchain.cli.main`."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from satchain._safety import check_dir_outputs, check_run_dir
from satchain.cli._common import handle_errors, print_error, say, system_from_options
from satchain.cli.options import JsonOpt, PresetOpt, SystemOpt

__all__ = ["design"]


@handle_errors
def design(
    vary: Annotated[
        list[str],
        typer.Option(
            "--vary", help="the key to vary and its range, KEY=LO:HI, e.g. optics.aperture_diameter_m=0.2:1.5"
        ),
    ],
    target: Annotated[
        list[str],
        typer.Option("--target", help="a target, QUANTITY OP NUMBER with OP one of >=, <=, >, <; repeat for more"),
    ],
    preset: PresetOpt = None,
    system: SystemOpt = None,
    json_out: JsonOpt = False,
    out: Annotated[
        Path | None,
        typer.Option("-o", "--out", help="write design.json here (two keys: also feasibility.csv and feasibility.png)"),
    ] = None,
    grid: Annotated[int, typer.Option("--grid", help="points per key of a two-key feasibility map", min=3)] = 21,
) -> None:
    """Find the range of one system key that meets every target, by the budget.

    Each target names a budget quantity: niirs (GIQE 5), rer, rer_act, rer_alt, snr (the contrast SNR the GIQE
    uses), mtf_nyquist_act, mtf_nyquist_alt, gsd_m or q (lambda N / pitch), e.g. --target "niirs>=5.2".

    The key is varied over LO..HI with every other key held fixed, except the one that follows it: varying
    optics.aperture_diameter_m holds the focal length, so the f-number (and Q) follow. The output says which.

    A coarse scan brackets each target's sign change and a root finder (Brent) finds it, so an end of the answer
    is where its binding target is met exactly, not a grid point. Each end lists every target's value and margin.

    With two --vary keys the answer is a feasibility map on a --grid x --grid grid of the two keys: each
    target's margin per cell, the feasible cells, and with -o DIR feasibility.csv and feasibility.png (the
    feasible cells shaded, each target's margin = 0 line drawn).

    Exit status 1 when no value meets every target (each unreachable target is named with the best value found),
    2 for bad input (an unknown key or quantity, a range outside the key's allowed range, a target that cannot be
    parsed).
    """
    from satchain.errors import ConfigError
    from satchain.studies.design import design as run_design
    from satchain.studies.design import parse_target, parse_vary

    if len(vary) not in (1, 2):
        raise ConfigError(f"--vary given {len(vary)} times: give one key (a range) or two (a feasibility map)")
    ranges = [parse_vary(v) for v in vary]
    targets = [parse_target(t) for t in target]
    check_dir_outputs(out, ["design.json", "feasibility.csv", "feasibility.png"], {"--system": system})
    if out is not None:
        check_run_dir(out, kind="budget")  # a user's folder is refused, never overwritten
    sys_ = system_from_options(preset, system)
    if len(ranges) == 2:
        return _map(sys_, ranges, targets, json_out, out, grid)
    result = run_design(sys_, *ranges[0], targets)
    if json_out:
        typer.echo(json.dumps(result.to_dict(), indent=2))
    else:
        _print(result)
    if out is not None:
        _write_json(out, result.to_dict())
    _unreachable(result.unreachable() if not result.feasible else [])


def _write_json(out: Path, data: dict) -> None:
    from satchain._safety import write_run_marker
    from satchain.report._save import write_text

    out.mkdir(parents=True, exist_ok=True)
    write_run_marker(out, kind="budget")  # satchain's own: a later design -o may write here again
    write_text(out / "design.json", json.dumps(data, indent=2) + "\n")


def _unreachable(lines: list[str]) -> None:
    from satchain.errors import ConfigError

    for line in lines:
        print_error(ConfigError(line))
    if lines:
        raise typer.Exit(1)


def _map(sys_, ranges, targets, json_out: bool, out: Path | None, grid: int) -> None:
    from satchain.studies.design_map import feasibility_map

    fmap = feasibility_map(sys_, ranges, targets, n=grid)
    d = fmap.to_dict()
    if json_out:
        typer.echo(json.dumps(d, indent=2))
    else:
        say("; ".join(d["held_fixed"]))
        say("targets: " + ", ".join(d["targets"]))
        say(f"feasible: {d['feasible_cells']} of {d['cells']} grid cells")
        for k, r in d["feasible_ranges_on_the_grid"].items():
            say(f"  {k}: " + (f"{r[0]:.6g} .. {r[1]:.6g}" if r else "none"))
    if out is not None:
        from satchain.report.design_map import write_feasibility_map

        _write_json(out, d)
        for p in write_feasibility_map(fmap, out):
            say(f"wrote {p}")
    _unreachable(fmap.unreachable())


def _print(result) -> None:
    say(
        f"{result.key} in [{result.lo:g}, {result.hi:g}] ({result.held_fixed}"
        + (f"; {result.follows} follows)" if result.follows else ")")
    )
    say("targets: " + ", ".join(map(str, result.targets)))
    if not result.feasible:
        say("feasible: none")
        return
    for iv in result.intervals:
        say(f"feasible: {iv['lo']:.6g} .. {iv['hi']:.6g}")
        for end in ("lo", "hi"):
            bind = iv[f"{end}_binding"]
            why = f"binding: {bind}" if bind else "end of the range"
            say(f"  at {iv[end]:.6g} ({why})")
            for t in result.targets:
                say(
                    f"    {str(t):<24} value {iv['values_' + end][t.quantity]:.6g}  margin "
                    f"{iv['margins_' + end][str(t)]:+.4g}"
                )
