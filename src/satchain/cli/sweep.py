"""``satchain simulate IN1 IN2 ... --sweep KEY=V1,V2,... -o DIR``: many cases into one directory (see
:mod:`satchain.engine.sweep`), with a progress bar across the cases and a one-line summary."""

from __future__ import annotations

import signal
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer
from rich.text import Text

from satchain._safety import terminate_as_interrupt
from satchain.cli._common import console, err_console
from satchain.errors import ConfigError

if TYPE_CHECKING:
    from satchain._safety import _Received

__all__ = ["simulate_cases"]

#: The suffixes that say ``-o`` names a file, where a sweep needs a directory.
_FILE_SUFFIXES = (".tif", ".tiff", ".png", ".npy", ".json", ".csv")


class _CaseBars:
    """``progress(stage, done, total)`` of a sweep: one bar across the cases, one for the current case's stage."""

    def __init__(self) -> None:
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        self.bar = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            console=err_console,
            disable=not err_console.is_terminal,  # no bar in logs and pipes: an error stays one line
        )
        self.cases = self.bar.add_task("cases", total=None)
        self.stage = self.bar.add_task("", total=None, visible=False)
        self.started = False  # whether the cases began (validation passed, the manifest written)
        self.received: _Received | None = None  # satchain._safety's record of a signal (checked at every step)

    def __call__(self, stage: str, done: int, total: int) -> None:
        if self.received is not None:
            self.received.check()  # a signal whose exception was swallowed stops the sweep here
        if stage == "cases":
            self.started = True
            self.bar.update(self.cases, completed=done, total=total)
            self.bar.update(self.stage, visible=False)
        else:
            self.bar.update(self.stage, description=f"  {stage}", completed=done, total=total, visible=True)


def simulate_cases(
    inputs: Sequence[str],
    out: Path,
    system,
    *,
    sweep_texts: Sequence[str],
    seed: int,
    focal_plane: Path | None,
    options: Mapping[str, Any],
    names: Mapping[str, str],
) -> None:
    """Run the sweep for ``satchain simulate``, print the summary; exit 2 (a failed case) or 128 + signal."""
    from satchain.engine.sweep import parse_sweep, read_manifest, simulate_sweep

    if focal_plane is not None:
        raise ConfigError(
            "--focal-plane: writes one focal-plane image, so it applies to one INPUT without --sweep; leave it out"
        )
    if out.suffix.lower() in _FILE_SUFFIXES:
        raise ConfigError(
            f"-o {str(out)!r}: with several inputs or --sweep, -o is a directory (one image per case and "
            "manifest.json / manifest.csv); give a directory, e.g. -o sweep_out"
        )
    sweep = parse_sweep(sweep_texts, option="--sweep")
    names = {**names, "sweep": "--sweep", "inputs": "INPUT", "out_dir": "-o"}
    bars = _CaseBars()
    try:
        with bars.bar, terminate_as_interrupt() as bars.received:
            cases = simulate_sweep(inputs, system, out, sweep=sweep, seed=seed, progress=bars, notify=_say,
                                   names=names, **options)  # fmt: skip
    except KeyboardInterrupt as exc:
        if bars.started:
            _summary(read_manifest(out), out)
        signum = getattr(exc, "signum", signal.SIGINT)
        exec("pass")  # noqa: S102 (resets CPython's unhandled-KeyboardInterrupt flag: see satchain.cli._common.interrupted)
        err_console.print(
            Text(f"interrupted ({signal.Signals(signum).name}): ", style="bold red")
            + Text(
                f"the case in progress was removed; {out / 'manifest.json'} lists the cases written"
                if bars.started
                else "nothing was written"
            ),
            highlight=False,
            soft_wrap=True,
        )
        raise typer.Exit(128 + int(signum)) from None
    except Exception:
        if bars.started:  # a case failed: say what was written before the error line
            _summary(read_manifest(out), out)
        raise
    _summary(cases, out)


def _summary(cases, out: Path) -> None:
    """One line: how many cases were written, which one failed, where the manifest is."""
    written = sum(c.status == "written" for c in cases)
    failed = [c for c in cases if c.status in ("failed", "interrupted")]
    tail = ""
    if failed:
        c = failed[0]
        tail = f" (case {c.case}, {c.id}, {c.status}; {sum(c.status == 'not run' for c in cases)} not run)"
    _say(f"simulated {written} of {len(cases)} cases into {out}{tail}; manifest.json and manifest.csv list them")


def _say(message: str) -> None:
    console.print(message, markup=False, highlight=False, soft_wrap=True)
