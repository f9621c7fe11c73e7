"""``satchain design``: the inverse question by the budget, which values of a system key meet every target
(:func:`satchain.study.design.design`). Registered on the app by :mod:`satchain.cli.main`."""

from __future__ import annotations

import json
from typing import Annotated

import typer

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
) -> None:
    """Find the range of one system key that meets every target, by the budget.

    Each target names a budget quantity: niirs (GIQE 5), rer, rer_act, rer_alt, snr (the contrast SNR the GIQE
    uses), mtf_nyquist_act, mtf_nyquist_alt, gsd_m or q (lambda N / pitch), e.g. --target "niirs>=5.2".

    The key is varied over LO..HI with every other key held fixed, except the one that follows it: varying
    optics.aperture_diameter_m holds the focal length, so the f-number (and Q) follow. The output says which.

    A coarse scan brackets each target's sign change and a root finder (Brent) finds it, so an end of the answer
    is where its binding target is met exactly, not a grid point. Each end lists every target's value and margin.

    Exit status 1 when no value meets every target (each unreachable target is named with the best value found),
    2 for bad input (an unknown key or quantity, a range outside the key's allowed range, a target that cannot be
    parsed).
    """
    from satchain.errors import ConfigError
    from satchain.study.design import design as run_design
    from satchain.study.design import parse_target, parse_vary

    if len(vary) != 1:
        raise ConfigError(f"--vary given {len(vary)} times: give it once (one key)")
    key, lo, hi = parse_vary(vary[0])
    targets = [parse_target(t) for t in target]
    sys_ = system_from_options(preset, system)
    result = run_design(sys_, key, lo, hi, targets)
    if json_out:
        typer.echo(json.dumps(result.to_dict(), indent=2))
    else:
        _print(result)
    if not result.feasible:
        for line in result.unreachable():
            print_error(ConfigError(line))
        raise typer.Exit(1)


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
