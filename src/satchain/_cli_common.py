"""What every satchain command shares: consoles and the error handler (one clear line, exit status 2)."""

from __future__ import annotations

import functools
import math
import shutil

import typer
from rich.console import Console

from satchain.errors import ConfigError, SatchainError

__all__ = ["console", "err_console", "handle_errors", "parse_numbers"]

console = Console(width=max(shutil.get_terminal_size((150, 40)).columns, 120))
err_console = Console(stderr=True, soft_wrap=True)


def handle_errors(fn):
    """Turn satchain's errors into one clear line on stderr and exit status 2 (no traceback)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except SatchainError as exc:
            err_console.print(f"[bold red]error:[/] {exc}", highlight=False)
            raise typer.Exit(2) from None

    return wrapper


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
