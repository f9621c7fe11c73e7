"""``satchain study``: the cases of a study file, every one validated before any runs, run (at depth "run") on
local processes or a Dask cluster, and their table and page (:mod:`satchain.studies.api`; the study file:
:mod:`satchain.config.study`). Registered on the app by :mod:`satchain.cli.main`."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated, Any

import typer

from satchain.cli._common import err_console, handle_errors, handles_interrupts, say

__all__ = ["study"]


@handle_errors
@handles_interrupts
def study(
    study_file: Annotated[
        Path | None, typer.Argument(help="the study file (TOML: its base, axes and study tables); or --example")
    ] = None,
    out: Annotated[
        Path | None, typer.Option("-o", "--out", help="the study's folder (new, empty, or this study's: resumed)")
    ] = None,
    example: Annotated[
        str | None,
        typer.Option("--example", help="run a packaged study instead: aperture-aberration (the paper's study)"),
    ] = None,
    workers: Annotated[
        int | None,
        typer.Option("--workers", min=1, max=1024, help="cases run at once on local processes (default: the CPUs)"),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option(
            "--scheduler",
            help="run the cases on Dask: 'local' (a cluster of --workers processes here) or a scheduler's address "
            "(tcp://host:8786; the workers must see the inputs at the same paths)",
        ),
    ] = None,
    max_cases: Annotated[
        int | None,
        typer.Option("--max-cases", help="allow up to this many cases (default 10,000; more are refused)", min=1),
    ] = None,
) -> None:
    """Run a design study: the cases of a base run configuration over one or more axes.

    The study file holds a base table (a run configuration: file = "run.toml", relative to the study file, or
    its tables inline), one or more axes tables (key, and values = [...] or start/stop/num or start/stop/step)
    and a study table (depth, repeats, zip, reports). The cases are the axes' cartesian product (zip = true: taken
    together). Every case is validated before any case runs: a bad value names its case, key and allowed
    range, and nothing is written.

    depth = "budget": the predicted budget per case. depth = "run": each case (x repeats) through the whole
    chain, in parallel, each into DIR/cases/<case>/ (results.json, config.toml, case.json, and report.html as
    the study table's reports asks). Rerun the same command to resume: finished cases are kept. A case that fails is
    recorded with its one-line error and the study goes on.

    DIR/study.csv and DIR/study.parquet: one row per case x figure of merit (axes' values, case, seed,
    figure, measured, predicted, error, sigma, z, pass) with the case's budget (GSD, Q, MTF at Nyquist
    ACT/ALT, SNR, NIIRS); DIR/study.html: each figure against each axis, a map for two axes, the case table.

    Exit status 0 when every case ran and passed its checks, 1 when a case failed a check or errored, 2 for
    bad input (nothing written), 128 + signal when interrupted (finished cases kept).
    """
    from satchain.errors import ConfigError

    if out is None:
        raise ConfigError("-o/--out: give the study's folder")
    if (study_file is None) == (example is None):
        raise ConfigError("give a study file or --example NAME (one, not both)")
    if study_file is not None:
        from satchain._safety import check_dir_outputs

        check_dir_outputs(out, ["study.csv", "study.parquet", "study.html", "study.json"], {"STUDY": study_file})
    from satchain.studies.api import study as run_study

    bar, update = _bar()
    t0 = time.perf_counter()
    try:
        with bar:
            result = run_study(study_file, out, example=example, workers=workers, scheduler=scheduler,
                               max_cases=max_cases, progress=update)  # fmt: skip
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM: the finished cases are kept
        raise typer.Exit(_interrupted(exc, out, update)) from None
    for line in result.held_fixed:
        say(line)
    _summary(result, time.perf_counter() - t0)
    if not result.passed:
        raise typer.Exit(1)


def _bar() -> tuple[Any, Any]:
    """A progress bar of cases: done / failed / left and the time to go (none in logs and pipes)."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    bar = Progress(
        TextColumn("[bold]cases"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[status]}"),
        TimeRemainingColumn(),
        console=err_console,
        disable=not err_console.is_terminal,
    )
    task = bar.add_task("cases", total=None, status="")

    class Update:
        finished = 0

        def __call__(self, p: Any) -> None:
            self.finished = p.done + p.failed
            left = p.total - p.done - p.failed
            bar.update(task, completed=p.done + p.failed, total=p.total,
                       status=f"done {p.done}  failed {p.failed}  left {left}")  # fmt: skip

    return bar, Update()


def _interrupted(exc: KeyboardInterrupt, out: Path, update: Any) -> int:
    import signal

    from rich.text import Text

    signum = getattr(exc, "signum", signal.SIGINT)
    exec("pass")  # noqa: S102 (resets CPython's unhandled-KeyboardInterrupt flag: see satchain.cli._common.interrupted)
    n = update.finished
    err_console.print(
        Text(f"interrupted ({signal.Signals(signum).name}): ", style="bold red")
        + Text(
            f"the study stopped; {n} finished case{'s' if n != 1 else ''} kept under {str(out / 'cases')!r} "
            "(the unfinished ones left nothing); rerun the same command to finish it"
        ),
        highlight=False,
        soft_wrap=True,
    )
    return 128 + int(signum)


def _summary(result: Any, elapsed: float) -> None:
    from rich.text import Text

    if result.depth == "budget":
        say(f"{result.n_cases} cases, depth = 'budget' (predictions only)")
    else:
        resumed = f", {result.resumed} kept from an earlier run" if result.resumed else ""
        rss = f"; peak memory per worker {result.peak_rss_mb:.0f} MB" if result.peak_rss_mb else ""
        say(
            f"{result.n_cases} cases, depth = 'run': {result.n_ok} ok, {result.n_failed} failed a check, "
            f"{result.n_error} errored{resumed} ({elapsed:.0f} s{rss})"
        )
        for folder, message in result.errors[:10]:
            err_console.print(Text("error ", style="bold red") + Text(f"{folder}: {message}"), highlight=False)
    for title, text in result.findings:
        say(f"{title}: {text}")
    say(f"table: {result.csv}  page: {result.page}")
