"""Every ``python -m satchain...`` command the documentation names runs a module that exists."""

from __future__ import annotations

import importlib
import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
COMMAND = re.compile(r"python3?\s+-m\s+(satchain(?:\.\w+)*)")


def documents() -> list[Path]:
    """README, docs/ and the package's own files (presets' comments, docstrings, data notes)."""
    src = ROOT / "src" / "satchain"
    found = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    return found + sorted(p for ext in ("*.toml", "*.py", "*.md") for p in src.rglob(ext))


def named_modules() -> dict[str, list[str]]:
    """``{module: [files naming it]}``."""
    out: dict[str, list[str]] = {}
    for path in documents():
        if path.is_file():
            for m in COMMAND.findall(path.read_text(encoding="utf-8")):
                out.setdefault(m, []).append(str(path.relative_to(ROOT)))
    return out


def test_the_commands_are_found_where_they_are_documented():
    named = named_modules()
    assert "README.md" in named.get("satchain.presets.paper", [])
    assert "src/satchain/presets/ankarasat3.toml" in named.get("satchain.presets.paper", [])
    assert COMMAND.findall("run `python -m satchain.presets.nosuch` or python3 -m satchain") == [
        "satchain.presets.nosuch",
        "satchain",
    ]


@pytest.mark.parametrize("module", sorted(named_modules()))
def test_every_named_module_imports_and_runs_as_main(module):
    spec = importlib.util.find_spec(module)
    assert spec is not None, f"python -m {module}: no such module (named in {named_modules()[module]})"
    if spec.submodule_search_locations is not None:  # a package runs its __main__
        assert importlib.util.find_spec(f"{module}.__main__") is not None, f"{module} has no __main__"
    else:
        importlib.import_module(module)
        assert 'if __name__ == "__main__":' in Path(spec.origin).read_text(encoding="utf-8"), module


def test_python_dash_m_satchain_is_the_satchain_command():
    """``python -m satchain`` runs the same CLI as the ``satchain`` script (help lists its commands; a bad
    option is the same one-line error, exit 2)."""
    import subprocess
    import sys

    ok = subprocess.run([sys.executable, "-m", "satchain", "--help"], capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0 and "run" in ok.stdout and "measure" in ok.stdout and "satchain" in ok.stdout
    bad = subprocess.run([sys.executable, "-m", "satchain", "run", "--no-such-option"], capture_output=True,
                         text=True, timeout=120)  # fmt: skip
    assert bad.returncode == 2 and "--no-such-option" in bad.stderr
