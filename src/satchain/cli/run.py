"""``satchain run``: the main job (predict, simulate, measure, compare and report) of a run configuration, into a
folder replaced atomically (:func:`satchain.run`); its exit status gates CI.

Registered on the app by :mod:`satchain.cli.main`.  (Once imported, this module is ``satchain.cli.run``: the
command is :func:`run` in it, or ``satchain.cli.main.run``.)
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table
from rich.text import Text

from satchain._safety import check_inputs_outside
from satchain.cli._common import console, err_console, handle_errors, handles_interrupts, print_warning, say
from satchain.cli._common import interrupted as _interrupted
from satchain.cli.options import PresetOpt

__all__ = ["run"]


def _print_run(result) -> None:
    from satchain.comparison import row_texts

    c = result.comparison
    n_na = len(c.rows) - c.n_checked  # n/a rows are counted apart: neither passed nor failed
    na = f", {n_na} n/a" if n_na else ""
    t = Table(title=f"{result.system.name}: measured vs predicted ({c.n_checked - c.n_failed}/{c.n_checked} pass{na})")
    cols: tuple[str, ...] = ("measured", "predicted", "error", "sigma", "z", "tolerance")
    if any(r.as_built is not None for r in c.rows):  # simulated as built: its prediction and z beside the design's
        cols = (*cols[:5], "predicted as built", "z as built", cols[5])
    t.add_column("figure of merit", justify="left")
    for col in (*cols, "result"):
        t.add_column(col, justify="right")
    for r in c.rows:
        cells = row_texts(r)
        style = {None: "", True: "green", False: "red"}[r.passed]
        verdict = Text(cells["result"], style=style)
        if r.tolerance_inside_noise:
            verdict.stylize("yellow", len(cells["result"].split(" (")[0]))
        t.add_row(Text(r.figure), *(cells[k] for k in cols), verdict)
    console.print(t)
    for r in c.rows:
        if r.passed is None and r.reason:
            err_console.print(Text("n/a: ", style="bold") + Text(f"{r.figure}: {r.reason}"), highlight=False)
    for w in result.warnings:
        print_warning(w)


@handle_errors
@handles_interrupts
def run(
    preset: PresetOpt = None,
    config: Annotated[Path | None, typer.Option("--config", help="run configuration TOML (see --print-config)")] = None,
    out: Annotated[Path, typer.Option("-o", "--out", help="output directory (replaced atomically)")] = Path(
        "satchain-run"
    ),
    print_config: Annotated[
        bool, typer.Option("--print-config", help="print the default configuration and exit")
    ] = False,
    exit_zero: Annotated[
        bool, typer.Option("--exit-zero", help="exit 0 even when a check fails (default: exit 1, to gate CI)")
    ] = False,
) -> None:
    """The main job: predict, simulate, measure, compare and report (report.html, results.json).

    Exit status: 0 when every check made passes (n/a rows aside), 1 when a check fails or none could be made
    (unless --exit-zero), 2 on an error.
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    import satchain
    from satchain.config.run import DEFAULT_CONFIG_TOML, RunConfig, load_run_config
    from satchain.pipeline import STAGES

    if print_config:
        print(DEFAULT_CONFIG_TOML, end="")
        return
    cfg = load_run_config(config)
    check_inputs_outside(
        out, {"--config": config, "system.file": cfg.system_path(), "as_built.file": cfg.as_built_path()}
    )
    if preset is not None:
        cfg = RunConfig.from_dict({**cfg.to_dict(), "system": {"preset": preset}}, base_dir=cfg.base_dir)
    bar = Progress(
        TextColumn("[bold]{task.description:<9}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
        console=err_console,
        disable=not err_console.is_terminal,
    )
    tasks = {name: bar.add_task(name, total=None, start=False) for name in STAGES}

    def update(stage: str, done: int, total: int) -> None:
        bar.start_task(tasks[stage])
        bar.update(tasks[stage], completed=done, total=total)

    previous = out.is_dir() and any(out.iterdir())
    try:
        with bar:
            result = satchain.run(cfg, out_dir=out, progress=update)
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM (satchain._safety.Interrupted)
        raise typer.Exit(_interrupted(exc, out, previous)) from None
    _print_run(result)
    console.print(f"report: {out / 'report.html'}   results: {out / 'results.json'}", markup=False, highlight=False)
    if result.kept_files:  # the user's files in the folder this run replaced
        n, shown = len(result.kept_files), ", ".join(result.kept_files[:5])
        more = f", ... ({n} in all)" if n > 5 else ""
        say(f"kept {n} file{'s' if n != 1 else ''} satchain did not write in {str(out)!r}: {shown}{more}")
    if result.passed is False and not exit_zero:
        n = result.comparison.n_failed
        err_console.print(f"[bold red]{n} check(s) failed[/] (exit status 1; --exit-zero to ignore)")
        raise typer.Exit(1)
    if result.comparison.n_checked == 0 and not exit_zero:  # a gate that checked nothing must not pass
        err_console.print(
            "[bold red]no check could be made[/]: every row is n/a (see the reasons above; "
            "exit status 1; --exit-zero to ignore)"
        )
        raise typer.Exit(1)


