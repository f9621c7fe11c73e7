"""``satchain measure``: image-quality measurements from image files (a typer sub-app, mounted by
:mod:`satchain.cli.main`).

Commands: ``edge``, ``star``, ``bars``, ``wedge`` (one target in a region; :mod:`satchain.cli.targets`),
``auto`` (every target of a scene, from its truth file; :mod:`satchain.cli.auto`), ``find`` (the slanted
edges found in an image, no truth file; :mod:`satchain.cli.find`), ``jitter`` (line-of-sight motion from a
long straight edge; :mod:`satchain.cli.jitter`) and ``registration`` (the subpixel offset between two bands;
:mod:`satchain.cli.registration`).  Images: TIFF (float or integer), PNG
(8/16-bit) and NPY, read by :func:`satchain.io.images.read_image`; the ground pixel size comes from ``--pixel-m`` or
the file's metadata.  Regions are ``X0,Y0,X1,Y1`` in pixels (x = column, y = row), half-open.  ``--json``
prints the result as JSON; ``-o DIR`` writes ``<command>.json`` and a figure there.  Bad input: one line on
stderr, exit status 2.  The options the commands share are defined once, in :mod:`satchain.cli.options`.

This module is where the commands are registered (the one place): imports flow one way,
``main -> measure -> targets, auto, find, jitter, registration -> options, output`` (modules of :mod:`satchain.cli`).
"""

from __future__ import annotations

import typer

from satchain.cli._common import ReflowGroup
from satchain.cli._common import handle_errors as _handle_errors
from satchain.cli._common import parse_numbers as _numbers
from satchain.cli.auto import auto
from satchain.cli.find import find
from satchain.cli.jitter import jitter
from satchain.cli.options import ImageArg, JsonOpt, OutOpt, PixelOpt, RoiOpt
from satchain.cli.options import load_image as _load
from satchain.cli.options import parse_origin as _origin
from satchain.cli.options import parse_roi as _roi
from satchain.cli.options import read_truth as _read_truth
from satchain.cli.output import curve_table as _curve_table
from satchain.cli.output import emit as _emit
from satchain.cli.output import fmt as _fmt
from satchain.cli.output import kv_table as _kv_table
from satchain.cli.output import pm as _pm
from satchain.cli.output import wide_console as _console
from satchain.cli.registration import registration
from satchain.cli.targets import bars, edge, star, wedge

__all__ = ["COMMANDS", "measure_app"]

measure_app = typer.Typer(
    name="measure",
    help="Measure image quality (slanted edge, Siemens star, bar targets, hyperbolic wedge) and line-of-sight "
    "motion (jitter, from a long edge) from images.",
    cls=ReflowGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

#: The ``measure`` commands, in the order ``--help`` lists them.
COMMANDS = {"edge": edge, "star": star, "bars": bars, "wedge": wedge, "auto": auto, "find": find, "jitter": jitter,
            "registration": registration}
for _name, _command in COMMANDS.items():
    measure_app.command(_name)(_command)

# the names this module had before the split (issue 18), for code that imported them from here
_OLD_NAMES = (ImageArg, JsonOpt, OutOpt, PixelOpt, RoiOpt, _handle_errors, _numbers, _load, _origin, _roi,
              _read_truth, _curve_table, _emit, _fmt, _kv_table, _pm, _console)  # fmt: skip
