"""``satchain study``: the cases of a study file, every one validated before any runs, and their table
(:mod:`satchain.studies.cases`; the study file: :mod:`satchain.config.study`). Registered on the app by
:mod:`satchain.cli.main`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from satchain.cli._common import handle_errors, say

__all__ = ["study"]


@handle_errors
def study(
    study_file: Annotated[Path, typer.Argument(help="the study file (TOML): [base], [[axes]] and [study]")],
    out: Annotated[Path, typer.Option("-o", "--out", help="the study's folder: study.csv is written here")],
    max_cases: Annotated[
        int | None,
        typer.Option("--max-cases", help="allow up to this many cases (default 10,000; more are refused)", min=1),
    ] = None,
) -> None:
    """Run a design study: the cases of a base run configuration over one or more axes.

    The study file holds [base] (a run configuration: file = "run.toml", relative to the study file, or its
    tables inline), one or more [[axes]] (key, and values = [...] or start/stop/num or start/stop/step) and
    [study] (depth, repeats, zip, reports). The cases are the axes' cartesian product (zip = true: taken
    together). Every case's system is built before any case runs: a bad value names its case, key and allowed
    range, and nothing is written.

    depth = "budget": DIR/study.csv holds one row per case x figure of merit (niirs, rer, snr, MTF at Nyquist,
    GSD, Q) with the prediction and the budget's derived quantities (GSD, Q, MTF at Nyquist ACT/ALT, SNR,
    NIIRS) of the case. depth = "run" (the whole chain per case) is not available yet.

    Exit status 2 for bad input (nothing written).
    """
    from satchain._safety import check_dir_outputs, check_run_dir
    from satchain.config.study import load_study
    from satchain.studies.cases import expand_cases, held_fixed, run_study

    spec = load_study(study_file)
    check_dir_outputs(out, ["study.csv"], {"STUDY": study_file})
    check_run_dir(out, kind="study")  # a user's folder is refused, never overwritten
    cases = expand_cases(spec, max_cases=max_cases)  # every case validated before anything is written
    for line in held_fixed(spec):
        say(line)
    path = run_study(spec, out, cases=cases)
    say(f"{len(cases)} cases, depth = {spec.study.depth!r}: wrote {path}")
