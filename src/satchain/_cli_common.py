"""What every satchain command shares: consoles and the error handler (one clear line, exit status 2)."""

from __future__ import annotations

import functools
import shutil

import typer
from rich.console import Console

from satchain.errors import SatchainError

__all__ = ["console", "err_console", "handle_errors"]

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
