"""Issue 30, point 8: the CLI's help reads well at any terminal width. typer/rich reflow the help text, so every
command's help is written as paragraphs (no hard line breaks inside one: they would survive as mid-sentence breaks
at a wide terminal, as ``satchain measure edge --help`` had), the commands panel gives each command's summary
unbroken, and no literal ``%%`` (an escape click never undoes in help text) is shown."""

from __future__ import annotations

import re

import pytest
import typer
import typer.rich_utils
from typer.testing import CliRunner

from satchain.cli.main import app

WIDTHS = (80, 200)
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")
_LIST_ITEM = re.compile(r"^(?:[-*]\s|\d+[.)]\s)")


def _paths(command, path=()):
    yield path
    for name, sub in sorted(getattr(command, "commands", {}).items()):
        yield from _paths(sub, (*path, name))


PATHS = list(_paths(typer.main.get_command(app)))


def _render(path: tuple[str, ...], width: int, monkeypatch) -> str:
    # typer reads TERMINAL_WIDTH (and forces a terminal on CI) once, at import: pin both for this rendering
    monkeypatch.setattr(typer.rich_utils, "MAX_WIDTH", width)
    monkeypatch.setattr(typer.rich_utils, "FORCE_TERMINAL", False)
    result = CliRunner().invoke(app, [*path, "--help"], env={"COLUMNS": str(width)}, terminal_width=width)
    assert result.exit_code == 0, (path, result.output)
    return _ANSI.sub("", result.output)


def _description(text: str) -> list[str]:
    """The help's description: the lines between the usage line and the first panel, less rich's indent."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.strip().startswith("Usage:")) + 1
    end = next((i for i, line in enumerate(lines) if line.lstrip().startswith("╭")), len(lines))
    return [line[1:].rstrip() if line.startswith(" ") else line.rstrip() for line in lines[start:end]]


def _hard_breaks(lines: list[str], room: int) -> list[str]:
    """Lines broken although the next line's first word would have fitted on them (rich wraps greedily, so such a
    break is one the text itself carried), list items aside."""
    found = []
    for line, following in zip(lines, lines[1:], strict=False):
        if not line.strip() or not following.strip() or _LIST_ITEM.match(following.strip()):
            continue
        word = following.split()[0]
        if len(line) + 1 + len(word) <= room:
            found.append(f"{line!r} / {following!r}")
    return found


def _command_rows(text: str) -> list[tuple[str, str, int]]:
    """The commands panel's rows as ``(name, description line, room)``: name is "" on a continuation line."""
    rows, inside = [], False
    for line in text.splitlines():
        if line.startswith("╭") and "Commands" in line:
            inside = True
        elif line.startswith("╰"):
            inside = False
        elif inside and line.startswith("│"):
            body = line[1 : line.rindex("│")]
            match = re.match(r"^ (\S+)?(\s+)(.*?)\s*$", body)
            name, text_start = match.group(1) or "", match.start(3)
            rows.append((name, match.group(3), len(body) - text_start - 1))
    return rows


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("path", PATHS, ids=lambda p: " ".join(p) or "satchain")
def test_help_has_no_hard_breaks_nor_escaped_percent(path, width, monkeypatch):
    text = _render(path, width, monkeypatch)
    assert "%%" not in text, f"satchain {' '.join(path)} --help shows a literal %%"
    assert "``" not in text, f"satchain {' '.join(path)} --help shows reST literals (``x``)"
    # rich reads [name] as markup: an unescaped "[[bands]]" showed as "[]"
    assert "[]" not in text, f"satchain {' '.join(path)} --help lost a [bracketed] word to rich markup"
    assert _hard_breaks(_description(text), width - 2) == [], f"satchain {' '.join(path)} --help (COLUMNS={width})"
    rows = _command_rows(text)
    breaks = [
        f"{prev!r} / {line!r}"
        for (_, prev, room), (name, line, _) in zip(rows, rows[1:], strict=False)
        if not name and line and len(prev) + 1 + len(line.split()[0]) <= room
    ]
    assert breaks == [], f"satchain {' '.join(path)} --help commands panel (COLUMNS={width})"


def test_measure_edge_reads_as_paragraphs_at_a_wide_terminal(monkeypatch):
    """The case the issue names: at 200 columns each line of the edge command's second paragraph but its last is
    filled to the width (it was broken where the docstring's source lines were, at about 110 characters)."""
    description = _description(_render(("measure", "edge"), 200, monkeypatch))
    start = next(i for i, line in enumerate(description) if line.startswith("The region must hold one straight"))
    end = description.index("", start)
    assert end - start >= 2, description
    assert all(len(line) > 170 for line in description[start : end - 1]), description[start:end]


def test_reflow_joins_the_lines_of_a_paragraph_and_keeps_paragraphs_lists_and_verbatim_blocks():
    from satchain.cli._common import reflow_help

    text = (
        "First line\nof the summary.\n\nA second\nparagraph.\n\n- one\n  item\n- two\n\n\b\nkept\nas is\n\fhidden\nnot"
    )
    assert reflow_help(text) == (
        "First line of the summary.\n\nA second paragraph.\n\n- one item\n- two\n\n\b\nkept\nas is\n\fhidden\nnot"
    )
    assert reflow_help(None) is None
    assert reflow_help("    Indented\n    docstring.\n") == "Indented docstring."
