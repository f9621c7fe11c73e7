"""The ``satchain`` command line: the root typer app, its callback (``--debug``, warnings as one line each) and the
registration of its commands, one module per command or command group (thin wrappers that parse arguments, call
the library and print): :mod:`satchain.cli.budget`, :mod:`satchain.cli.scene`, :mod:`satchain.cli.simulate`,
:mod:`satchain.cli.run`, :mod:`satchain.cli.measure` (a sub-app) and :mod:`satchain.cli.schema`."""

from __future__ import annotations

import satchain.cli._startup  # noqa: F401 (first: SIGTERM answered from the first import on)

# isort: split
import os
from typing import Annotated

import typer

from satchain.cli._common import ReflowGroup, print_warning, set_debug
from satchain.cli.budget import budget
from satchain.cli.design import design
from satchain.cli.measure import measure_app
from satchain.cli.run import run
from satchain.cli.scene import scene
from satchain.cli.schema import schema
from satchain.cli.simulate import simulate
from satchain.cli.study import study

__all__ = ["app", "budget", "design", "main", "run", "scene", "schema", "simulate", "study"]

app = typer.Typer(
    name="satchain",
    help="Satellite image-chain simulation and image-quality measurement.",
    cls=ReflowGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


@app.callback()
def _main(
    ctx: typer.Context,
    debug: Annotated[bool, typer.Option("--debug", help="show the traceback of an error (for bug reports)")] = False,
) -> None:
    """Satellite image-chain simulation and image-quality measurement."""
    set_debug(debug or os.environ.get("SATCHAIN_DEBUG", "") not in ("", "0"))
    _show_warnings(ctx)


def _show_warnings(ctx: typer.Context) -> None:
    """While a command runs, print satchain's warnings (an input used other than as it stands) as one
    ``warning: ...`` line each, once; other warnings as Python shows them."""
    import warnings

    from satchain.errors import SatchainWarning

    previous, seen = warnings.showwarning, set()

    def show(message, category, filename, lineno, file=None, line=None):
        if not issubclass(category, SatchainWarning):
            return previous(message, category, filename, lineno, file, line)
        if str(message) not in seen:
            seen.add(str(message))
            print_warning(str(message))

    warnings.showwarning = show
    ctx.call_on_close(lambda: setattr(warnings, "showwarning", previous))


# the commands, in the order `satchain --help` lists them
app.command()(budget)
app.command()(scene)
app.command()(simulate)
app.command()(run)
app.add_typer(measure_app, name="measure", help="Measure image quality: edge, star, bars, wedge, auto, find, jitter.")
app.command("schema")(schema)
app.command("design")(design)
app.command("study")(study)


def main() -> None:  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
