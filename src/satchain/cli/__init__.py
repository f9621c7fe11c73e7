"""The command line: ``satchain`` (:data:`app`, a typer app) and its commands, one module per command or command
group (``measure``'s subcommands in :mod:`satchain.cli.measure`, ...), shared options in :mod:`satchain.cli.options`
and :mod:`satchain.cli._common`.

``satchain.cli.app`` and the other names of :mod:`satchain.cli.main` are read from there on first use (PEP 562), so
importing a command module does not build the whole app.  A command's module shadows its function here:
``satchain.cli.run`` is the module :mod:`satchain.cli.run` (always, also on first use); the command is
``satchain.cli.main.run``.
"""

from __future__ import annotations

import importlib
from typing import Any


def __getattr__(name: str) -> Any:
    if name.startswith("__"):
        raise AttributeError(name)
    main = importlib.import_module("satchain.cli.main")
    if name in globals():  # a submodule (satchain.cli.run, ...) that importing main has just bound here
        return globals()[name]
    return getattr(main, name)
