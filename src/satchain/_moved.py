"""Modules moved when the package root was regrouped (issue 30): the old dotted names still import, with a
:class:`~satchain.errors.SatchainDeprecationWarning` naming the new one, until
:data:`~satchain._deprecate.REMOVED_IN`.

An old name imports as a thin module that reads and writes through to the new one (``satchain.quality.giqe5`` is
``satchain.prediction.quality.giqe5``; a test's ``monkeypatch.setattr("satchain.system.X", ...)`` patches the new
module). CHANGELOG.md lists every move (tests/test_changelog_aliases.py keeps the two in agreement).

Examples
--------
The first import of an old name warns ("satchain.quality is deprecated in satchain 0.1 and will be removed in 0.2:
it moved to satchain.prediction.quality"); what it gives is the new module's:

>>> import warnings
>>> from satchain.prediction.quality import giqe5
>>> with warnings.catch_warnings():
...     warnings.simplefilter("ignore")
...     from satchain.quality import giqe5 as old
>>> old is giqe5
True
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings
from collections.abc import Sequence
from typing import Any

from satchain._deprecate import DEPRECATED_IN, REMOVED_IN
from satchain.errors import SatchainDeprecationWarning

#: old module -> new module (the root's modules regrouped into cli/, prediction/, config/ and io/).
MOVED: dict[str, str] = {
    "satchain._cli_common": "satchain.cli._common",
    "satchain.cli_options": "satchain.cli.options",
    "satchain.cli_output": "satchain.cli.output",
    "satchain.cli_auto": "satchain.cli.auto",
    "satchain.cli_find": "satchain.cli.find",
    "satchain.cli_jitter": "satchain.cli.jitter",
    "satchain.cli_measure": "satchain.cli.measure",
    "satchain.cli_schema": "satchain.cli.schema",
    "satchain.cli_sweep": "satchain.cli.sweep",
    "satchain.cli_targets": "satchain.cli.targets",
    "satchain._startup": "satchain.cli._startup",
    "satchain.quality": "satchain.prediction.quality",
    "satchain.star_prediction": "satchain.prediction.star",
    "satchain.wedge_prediction": "satchain.prediction.wedge",
    "satchain.bar_prediction": "satchain.prediction.bars",
    "satchain.target_image": "satchain.prediction.target_image",
    "satchain.image_geometry": "satchain.prediction.image_geometry",
    "satchain.check_sigma": "satchain.comparison.sigma",
    "satchain.ctf": "satchain.tf.ctf",
    "satchain.system": "satchain.config.system",
    "satchain.sections": "satchain.config.sections",
    "satchain.sections_motion": "satchain.config.sections_motion",
    "satchain._sections_base": "satchain.config._base",
    "satchain.runconfig": "satchain.config.run",
    "satchain.schema": "satchain.config.schema",
    "satchain.raster": "satchain.io.raster",
    "satchain._imagemeta": "satchain.io.imagemeta",
    "satchain._commit": "satchain.io._commit",
    "satchain._runfolder": "satchain.io.runfolder",
    "satchain._memory": "satchain.engine._malloc",
}


class _Alias(types.ModuleType):
    """An old module name: every attribute read and written through to the module it moved to."""

    def __init__(self, name: str, target: types.ModuleType) -> None:
        super().__init__(name)
        object.__setattr__(self, "_target", target)
        object.__setattr__(self, "_saved", {})  # the target's values that writes through this name replaced

    def __getattr__(self, name: str) -> Any:
        return getattr(object.__getattribute__(self, "_target"), name)

    def __setattr__(self, name: str, value: Any) -> None:
        if name.startswith("__") and name.endswith("__"):
            object.__setattr__(self, name, value)
            return
        target, saved = object.__getattribute__(self, "_target"), object.__getattribute__(self, "_saved")
        if name in saved and saved[name] is value:
            del saved[name]  # the original put back
        elif name not in saved and hasattr(target, name):
            saved[name] = getattr(target, name)
        setattr(target, name, value)

    def __delattr__(self, name: str) -> None:
        """Deleting a name written through this one puts the target's value back (a monkeypatch that finds no
        such name in this module's own dict undoes its write by deleting it): the moved module keeps its names."""
        target, saved = object.__getattribute__(self, "_target"), object.__getattribute__(self, "_saved")
        if name in saved:
            setattr(target, name, saved.pop(name))
        else:
            delattr(target, name)

    def __dir__(self) -> list[str]:
        return dir(object.__getattribute__(self, "_target"))


class _AliasLoader(importlib.abc.Loader):
    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        new = MOVED[spec.name]
        warnings.warn(
            f"{spec.name} is deprecated in satchain {DEPRECATED_IN} and will be removed in {REMOVED_IN}: "
            f"it moved to {new}",
            SatchainDeprecationWarning,
            stacklevel=2,
        )
        return _Alias(spec.name, importlib.import_module(new))

    def exec_module(self, module: types.ModuleType) -> None:
        return None


class _AliasFinder(importlib.abc.MetaPathFinder):
    """Finds the old names of :data:`MOVED` (only those: every other import goes on to the normal finders)."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: types.ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, _AliasLoader())


def install() -> None:
    """Put the finder on ``sys.meta_path`` once (``import satchain`` does)."""
    if not any(isinstance(f, _AliasFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, _AliasFinder())
