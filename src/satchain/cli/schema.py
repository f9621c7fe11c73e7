"""``satchain schema``: the JSON Schema of a system file, a run configuration, a study file or results.json, for editors
(taplo / Even Better TOML) and tools. Registered on the app by :mod:`satchain.cli.main`; the schemas come from
:mod:`satchain.config.schema` (imported when the command runs, so that ``satchain --help`` stays fast)."""

from __future__ import annotations

import enum
from typing import Annotated

import typer

from satchain.cli._common import handle_errors

__all__ = ["schema"]


class SchemaKind(str, enum.Enum):
    system = "system"
    run = "run"
    study = "study"
    results = "results"


@handle_errors
def schema(
    kind: Annotated[
        SchemaKind,
        typer.Argument(
            help="system (a system file), run (a run configuration), study (a study file) or results (results.json)"
        ),
    ],
) -> None:
    """Print the JSON Schema that validates a system file, a run configuration, a study file or a results.json.

    Save it beside your files, e.g. satchain schema system > system.schema.json

    A TOML file whose first line is #:schema ./system.schema.json then gets completion and validation in taplo.

    Even Better TOML (VS Code) shows each key's description, unit and range, and flags a misspelt key.
    """
    import json

    if kind.value == "results":
        from satchain.results import results_schema

        made = results_schema()
    else:
        from satchain.config.schema import schema as make_schema

        made = make_schema(kind.value)
    typer.echo(json.dumps(made, indent=2))
