"""The command line: ``satchain`` (:data:`app`, a typer app) and its commands, one module per command or command
group (``measure``'s subcommands in :mod:`satchain.cli.measure`, ...), shared options in :mod:`satchain.cli.options`
and :mod:`satchain.cli._common`.

``satchain.cli.app`` and every name of the former ``satchain/cli.py`` module are read from :mod:`satchain.cli.main`
on first use (PEP 562), so importing a command module does not build the whole app.
"""

from __future__ import annotations

import importlib
from typing import Any


def __getattr__(name: str) -> Any:
    if name.startswith("__"):
        raise AttributeError(name)
    return getattr(importlib.import_module("satchain.cli.main"), name)
