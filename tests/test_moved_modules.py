"""The regrouped package root (issue 30): every moved module still imports under its old dotted name, with a
:class:`~satchain.errors.SatchainDeprecationWarning` naming the new one, reading and writing through to it;
CHANGELOG.md lists every move; satchain's own code never imports an old name; the root keeps at most 15 modules."""

from __future__ import annotations

import importlib
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from satchain._moved import MOVED
from satchain.errors import SatchainDeprecationWarning

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "satchain"


@pytest.mark.parametrize("old", sorted(MOVED))
def test_old_name_imports_with_a_warning_naming_the_new_one(old):
    new = importlib.import_module(MOVED[old])
    sys.modules.pop(old, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        alias = importlib.import_module(old)
    messages = [str(w.message) for w in caught if issubclass(w.category, SatchainDeprecationWarning)]
    assert len(messages) == 1 and MOVED[old] in messages[0] and "0.2" in messages[0], messages
    public = [n for n in vars(new) if not n.startswith("__")]
    assert public, MOVED[old]
    for name in public:
        assert getattr(alias, name) is getattr(new, name), name
    assert set(public) <= set(dir(alias))


def test_the_old_name_writes_through_to_the_new_module(monkeypatch):
    import satchain.config.system as new

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SatchainDeprecationWarning)
        import satchain.system as old
    sentinel = object()
    monkeypatch.setattr(old, "load_preset", sentinel)
    assert new.load_preset is sentinel
    monkeypatch.undo()
    assert new.load_preset is not sentinel


def test_from_package_import_old_module_name(monkeypatch):
    import satchain

    monkeypatch.delitem(sys.modules, "satchain.ctf", raising=False)
    monkeypatch.delattr(satchain, "ctf", raising=False)  # an earlier import set it on the package
    with pytest.warns(SatchainDeprecationWarning, match=r"satchain\.tf\.ctf"):
        from satchain import ctf
    from satchain.tf.ctf import coltman_ctf

    assert ctf.coltman_ctf is coltman_ctf


def test_the_new_packages_keep_the_former_modules_names_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error", SatchainDeprecationWarning)
        import satchain.cli
        import satchain.io
        import satchain.prediction
        from satchain.cli.main import app
        from satchain.io.images import write_tiff
        from satchain.prediction.core import predict

        assert satchain.cli.app is app
        assert satchain.prediction.predict is predict
        assert satchain.io.write_tiff is write_tiff
    with pytest.raises(AttributeError):
        _ = satchain.prediction.no_such_name


def test_changelog_lists_every_move():
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    missing = [f"{o} -> {n}" for o, n in MOVED.items() if f"`{o}` -> `{n}`" not in text]
    assert not missing


def test_no_moved_module_is_also_a_real_file():
    """An old name is only an alias: a file left behind under it would shadow nothing and confuse everyone."""
    for old in MOVED:
        rel = Path(*old.split(".")[1:])
        assert not (PACKAGE / rel.with_suffix(".py")).exists(), old
        assert not (PACKAGE / rel / "__init__.py").exists(), old


def test_the_package_root_keeps_at_most_15_modules():
    modules = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(modules) <= 15, modules


def test_satchain_itself_never_imports_an_old_name():
    """Every module of satchain imports with the deprecation warning turned into an error (in a fresh interpreter,
    so nothing earlier in this session has imported an alias already)."""
    mods = []
    for p in sorted(PACKAGE.rglob("*.py")):
        parts = p.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__main__":
            continue
        mods.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    code = (
        "import importlib, warnings\n"
        "from satchain.errors import SatchainDeprecationWarning\n"
        "warnings.simplefilter('error', SatchainDeprecationWarning)\n"
        f"for m in {mods!r}:\n"
        "    try:\n"
        "        importlib.import_module(m)\n"
        "    except ImportError as e:\n"
        "        if 'dask' in str(e) or 'distributed' in str(e) or 'zarr' in str(e):\n"
        "            continue\n"
        "        raise\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
