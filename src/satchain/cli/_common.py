"""What every satchain command shares: consoles, the error handler (one clear line, exit status 2), progress bars,
and the system a command's ``--preset`` / ``--system`` name."""

from __future__ import annotations

import functools
import inspect
import logging
import math
import os
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import click
import typer
from rich.console import Console
from rich.text import Text

from satchain._safety import end_startup
from satchain.errors import ConfigError, SatchainError

if TYPE_CHECKING:
    from rich.progress import Progress

    from satchain.config.system import ImagingSystem

__all__ = [
    "interrupted",
    "ReflowGroup",
    "console",
    "err_console",
    "error_line",
    "handle_errors",
    "handles_interrupts",
    "parse_numbers",
    "print_error",
    "print_warning",
    "progress_bar",
    "reflow_help",
    "say",
    "set_debug",
    "system_from_options",
]

# readers' own log lines (e.g. tifffile's "invalid offset") would add a second line to an error message
logging.getLogger("tifffile").setLevel(logging.ERROR)

console = Console(width=max(shutil.get_terminal_size((150, 40)).columns, 120))
err_console = Console(stderr=True, soft_wrap=True)


_DEBUG = {"on": os.environ.get("SATCHAIN_DEBUG", "") not in ("", "0")}


def set_debug(on: bool) -> None:
    """``--debug``: let errors propagate with their traceback instead of the one-line message."""
    _DEBUG["on"] = bool(on)


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def error_line(exc: BaseException) -> str:
    """The one-line message for any exception (satchain's own say what to fix; others get a hint).

    Examples
    --------
    >>> error_line(IsADirectoryError(21, "Is a directory", "/tmp"))
    "'/tmp': is a directory: give a file path"
    >>> error_line(KeyError("alt"))
    "unexpected KeyError: 'alt' (run with --debug for a traceback and please report it)"
    """
    if isinstance(exc, SatchainError):
        return _one_line(str(exc))
    if isinstance(exc, OSError):
        name = exc.filename if exc.filename is not None else ""
        what = (exc.strerror or str(exc)).lower()
        fixes = {
            IsADirectoryError: "give a file path",
            NotADirectoryError: "a parent of this path is a file, not a folder",
            FileNotFoundError: "check the path",
            FileExistsError: "a file is in the way: choose another path",
            PermissionError: "check the permissions or choose another path",
        }
        fix = next((v for k, v in fixes.items() if isinstance(exc, k)), "check the path and the free disk space")
        return _one_line(f"{str(name)!r}: {what}: {fix}" if name else f"{what}: {fix}")
    if isinstance(exc, MemoryError):
        return "out of memory: reduce the image or scene size (or the window), or use a machine with more memory"
    return _one_line(f"unexpected {type(exc).__name__}: {exc} (run with --debug for a traceback and please report it)")


def print_error(exc: BaseException) -> None:
    """Print ``error: <message>`` on stderr as plain text (no rich markup: ``[dask]`` stays as written)."""
    err_console.print(Text("error: ", style="bold red") + Text(error_line(exc)), highlight=False, soft_wrap=True)


def print_warning(message: str, console: Console | None = None) -> None:
    """Print ``warning: <message>`` on stderr as plain text (brackets in the message are kept)."""
    text = Text("warning: ", style="bold yellow") + Text(_one_line(message))
    (console or err_console).print(text, highlight=False, soft_wrap=True)


def say(message: str) -> None:
    """Print ``message`` on stdout as it is (no rich markup or highlighting)."""
    console.print(message, markup=False, highlight=False)


def handle_errors(fn):
    """Turn every error into one clear line on stderr and exit status 2 (no traceback unless ``--debug``).

    Typer's own exits and usage errors pass through unchanged (usage errors keep exit status 2).
    """

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if not getattr(fn, "handles_interrupts", False):  # it may write: SIGTERM's default action again
            end_startup()
        try:
            return fn(*args, **kwargs)
        except (typer.Exit, typer.Abort, click.exceptions.Exit, click.exceptions.Abort, click.ClickException):
            raise
        except Exception as exc:
            if _DEBUG["on"]:
                raise
            print_error(exc)
            raise typer.Exit(2) from None

    return wrapper


def handles_interrupts(fn):
    """A command that answers SIGTERM itself once it writes (satchain._safety.terminate_as_interrupt): the
    start-up's answer ("nothing was written") stays until then."""
    fn.handles_interrupts = True
    return fn


def system_from_options(preset: str | None, system: Path | None) -> ImagingSystem:
    """The system of a command's ``--preset`` or ``--system`` (one, not both; neither: ``ankarasat3``)."""
    from satchain.config.system import load_preset, load_system

    if preset and system:
        raise ConfigError(f"--preset {preset!r} and --system {str(system)!r}: give one, not both")
    if system is not None:
        return load_system(system)
    return load_preset(preset or "ankarasat3")


def progress_bar(description: str) -> tuple[Progress, Callable[[int, int], None]]:
    """A rich progress bar on stderr (none in logs and pipes) and the ``progress(done, total)`` callback that
    drives it."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    bar = Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=err_console,
        transient=False,
        disable=not err_console.is_terminal,  # no bar in logs and pipes: an error stays one line
    )
    task = bar.add_task(description, total=None)

    def update(done: int, total: int) -> None:
        bar.update(task, completed=done, total=total)

    return bar, update


def parse_numbers(name: str, text: str, n: int | None = None, *, minimum: float | None = None) -> list[float]:
    """Comma-separated finite numbers (exactly ``n`` when given, each >= ``minimum`` when given).

    Examples
    --------
    >>> parse_numbers("--freqs", "10, 42.5,85")
    [10.0, 42.5, 85.0]
    """
    try:
        vals = [float(t) for t in str(text).replace(" ", "").split(",") if t != ""]
    except ValueError:
        vals = []
    bad = not vals or (n is not None and len(vals) != n) or not all(math.isfinite(v) for v in vals)
    if bad or (minimum is not None and min(vals) < minimum):
        what = f"{n} comma-separated numbers" if n else "comma-separated numbers"
        floor = "" if minimum is None else f" >= {minimum:g}"
        raise ConfigError(f"{name} = {text!r}: must be {what}{floor}")
    return vals


_LITERAL = re.compile(r"``(.+?)``")  # a reST inline literal
_LIST_ITEM = re.compile(r"(?:[-*]\s|\d+[.)]\s)")


def reflow_help(text: str | None) -> str | None:
    """A command's help as typer/rich reflow it well: each paragraph one line (its source lines joined), so that
    it wraps at the terminal's width and not where the docstring was wrapped; paragraphs (a blank line between),
    list items (``- ``, ``* ``, ``1. ``) and click's verbatim blocks (a paragraph opening with ``\\b``) are kept,
    and so is everything after ``\\f`` (click's cut). The docstrings' reST literals read as the terminal shows
    them: an option as it is typed (``--center`` -> --center), anything else in quotes (``flags`` -> 'flags').

    Examples
    --------
    >>> reflow_help("A summary\\n    in two lines.\\n\\n- one\\n  item\\n- two")
    'A summary in two lines.\\n\\n- one item\\n- two'
    >>> print(reflow_help("Give ``--center`` in pixels; see ``flags``."))
    Give --center in pixels; see 'flags'.
    """
    if not text:
        return text
    head, cut, tail = inspect.cleandoc(text).partition("\f")
    head = _LITERAL.sub(lambda m: m[1] if m[1].startswith("-") else f"'{m[1]}'", head)
    paragraphs = []
    for paragraph in re.split(r"\n\s*\n", head.strip()):
        if paragraph.startswith("\b"):
            paragraphs.append(paragraph)
            continue
        items: list[str] = []
        for line in paragraph.splitlines():
            if items and not _LIST_ITEM.match(line.strip()):
                items[-1] = f"{items[-1]} {line.strip()}"
            else:
                items.append(line.strip())
        paragraphs.append("\n".join(items))
    return "\n\n".join(paragraphs) + (f"\n{cut}{tail}" if cut else "")


def _reflow_command(command: click.Command | typer.core.TyperCommand | typer.core.TyperGroup) -> None:
    command.help = reflow_help(command.help)
    for sub in getattr(command, "commands", {}).values():
        _reflow_command(sub)


class ReflowGroup(typer.core.TyperGroup):
    """The typer group of satchain's apps: its commands' help, and its sub-groups', written as wrapped source
    lines, is reflowed into paragraphs (:func:`reflow_help`) once, when typer builds the group."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        _reflow_command(self)


def interrupted(exc: KeyboardInterrupt, out: Path, previous: bool, *, what: str = "run",
                 kind: str = "staging folder") -> int:  # fmt: skip
    """Say what an interrupted run (or ``what``) left (its staging ``kind`` is already removed); the exit status
    128 + signal."""
    import signal

    signum = getattr(exc, "signum", signal.SIGINT)
    # CPython sets an "unhandled KeyboardInterrupt" flag whenever one escapes an exec() of a string (scipy's
    # array_api_compat runs one while it is imported), even though this one was handled; under `python -m` the
    # flag then makes the interpreter kill itself with SIGINT (exit -2) instead of exiting 128 + signum.  Any
    # exec() of a string that completes resets it.
    exec("pass")  # noqa: S102 (a constant: resets the flag, see above)
    kept = (
        f"the previous results in {str(out)!r} were kept unchanged"
        if previous
        else f"nothing was written to {str(out)!r}"
    )
    removed = "were" if kind.endswith("s") else "was"
    err_console.print(
        Text(f"interrupted ({signal.Signals(signum).name}): ", style="bold red")
        + Text(f"the {what} stopped and its {kind} {removed} removed; {kept}"),
        highlight=False,
        soft_wrap=True,
    )
    return 128 + int(signum)
