"""Every third-party package that ``src/satchain`` imports is declared in pyproject.toml, with a lower bound.

A package that is only pulled in by another one (click through typer, once) can vanish in its parent's next
release and break a fresh install; this test parses every import of the source tree, maps the module to the
distribution that provides it, and fails on an undeclared one. Imports at module level must be core
dependencies; a package declared only in an extra may be imported only inside a function (a lazy, guarded
import), so that ``pip install satchain`` without extras still imports every module.
"""

from __future__ import annotations

import ast
import functools
import re
import sys
from importlib.metadata import packages_distributions
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[1]
SRC = REPO / "src" / "satchain"


def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _requirement_name(req: str) -> str:
    return _norm(re.split(r"[\s\[<>=!~;]", req.strip(), maxsplit=1)[0])


@functools.cache
def _distributions() -> dict[str, list[str]]:
    """Top-level module -> the installed distributions providing it: read once per process (every installed
    distribution's file list is scanned, ~0.6 s; the environment does not change during the session)."""
    return dict(packages_distributions())


def _declared() -> tuple[dict[str, str], dict[str, str]]:
    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    core = {_requirement_name(r): r for r in project["dependencies"]}
    extras = {_requirement_name(r): r for reqs in project.get("optional-dependencies", {}).values() for r in reqs}
    return core, extras


def _imports(path: Path) -> list[tuple[str, bool, int]]:
    """(top-level module, imported at module level?, line) for every absolute import in a file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found = []
    module_level = {id(node) for node in tree.body}
    # imports under a module-level `if`/`try` (version switches) count as module level too
    for node in tree.body:
        if isinstance(node, (ast.If, ast.Try)):
            module_level |= {id(n) for n in ast.walk(node)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
        else:
            continue
        for name in names:
            found.append((name.split(".")[0], id(node) in module_level, node.lineno))
    return found


def _third_party(top: str) -> bool:
    return top not in sys.stdlib_module_names and top not in {"satchain", "__future__"}


SOURCES = sorted(SRC.rglob("*.py"))


def test_the_source_tree_is_found():
    assert len(SOURCES) > 50
    assert any(_third_party(t) for p in SOURCES for t, _, _ in _imports(p))


def test_every_declared_requirement_has_a_lower_bound():
    core, extras = _declared()
    for req in {**core, **extras}.values():
        assert ">=" in req or "==" in req, f"{req!r} has no lower bound"


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(SRC)))
def test_every_import_is_declared(path):
    core, extras = _declared()
    dists = _distributions()
    for top, at_module_level, line in _imports(path):
        if not _third_party(top):
            continue
        providers = {_norm(d) for d in dists.get(top, [])}
        if not providers and ";" in {**core, **extras}.get(_norm(top), ""):
            continue  # declared for other interpreters only (tomli on Python < 3.11): not installed here
        assert providers, f"{path.name}:{line} imports {top!r}, which no installed distribution provides"
        where = f"{path.relative_to(REPO)}:{line} imports {top!r} (from {sorted(providers)})"
        if at_module_level:
            assert providers & core.keys(), f"{where}: not a core dependency in pyproject.toml"
        else:
            assert providers & (core.keys() | extras.keys()), f"{where}: not declared in pyproject.toml"


def test_the_parser_sees_module_level_and_lazy_imports(tmp_path):
    p = tmp_path / "m.py"
    p.write_text(
        "import numpy as np\nfrom scipy import fft\ntry:\n    import tomllib\nexcept ImportError:\n"
        "    import tomli\ndef f():\n    import dask.array\n",
        encoding="utf-8",
    )
    got = {(t, lvl) for t, lvl, _ in _imports(p)}
    assert got == {("numpy", True), ("scipy", True), ("tomllib", True), ("tomli", True), ("dask", False)}
