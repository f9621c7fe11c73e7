"""satchain: Earth-observation satellite image-chain simulation and image-quality measurement.

The chain follows one line (see ARCHITECTURE): scene -> optics -> detector + motion -> sampled image,
with the same transfer functions used for prediction (``satchain.tf``) and simulation, and
independent measurement (``satchain.measure``) to check them.

The public API (imported lazily, so ``import satchain`` stays fast and never touches matplotlib's backend):

* design: :class:`ImagingSystem`, :func:`load_preset`, :func:`load_system`, :class:`SystemOTF`,
  :func:`coltman_ctf`, :func:`predict_quality`, :func:`budget` (the typed budget, :class:`SystemBudget`:
  what ``satchain budget --json`` prints);
* a whole run: :func:`run` (:class:`RunConfig` -> :class:`RunResult`), :func:`predict`, :func:`compare`;
* images: :func:`simulate`, :func:`simulate_image` (an array or a raster path -> the image with its transform),
  :func:`simulate_file` (file to COG), :func:`simulate_sweep` (several inputs x parameter sweeps),
  :func:`load_layout`, :func:`read_truth`, :class:`Rect`;
* measurement: :func:`measure_edge`, :func:`measure_star`, :func:`measure_bars`, :func:`measure_wedge`,
  :func:`measure_auto`, :func:`measure_snr`, :func:`find_edges`, :func:`measure_found_edges`,
  :func:`measure_registration` (band-to-band offset);
* the focal plane as flown: :func:`simulate_bands` / :func:`write_band_rasters` (every band of a
  ``[[bands]]`` camera from a spectral scene), :func:`simulate_cube` (from a reflectance cube),
  :func:`simulate_cfa` / :func:`measure_cfa` / :func:`predict_cfa`
  (a Bayer camera's raw mosaic, demosaicing, per-plane MTF and false colour), :func:`simulate_staggered` (two
  staggered arrays combined onto the half-pitch grid);
* design studies: :func:`study` (a study file's cases through the budget or the whole chain, on local processes
  or Dask: :class:`StudyResult`), :func:`design` (the range of a key, or the map of two, that meets targets);
* errors: :class:`SatchainError` and its subclasses.

Every entry point checks the types of its arguments and refuses a wrong one (a string or a boolean for a
number, None for an image, a file name for a truth record) with a one-line :class:`ParameterTypeError`.

Examples
--------
>>> import satchain
>>> s = satchain.load_preset("ankarasat3")
>>> round(s.gsd_m, 3)
0.49
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from satchain.errors import (
    ConfigError,
    InputError,
    ParameterTypeError,
    ResourceLimitError,
    SatchainError,
    SatchainIOError,
)

__version__ = "0.1.0"

from satchain import _moved  # noqa: E402 (the regrouped modules' old names still import, with a warning)

_moved.install()

#: public name -> module it lives in (imported on first use, PEP 562).
_LAZY = {
    "ImagingSystem": "satchain.config.system",
    "load_preset": "satchain.config.system",
    "load_system": "satchain.config.system",
    "run": "satchain.api",
    "RunResult": "satchain.api",
    "RunConfig": "satchain.config.run",
    "Tolerances": "satchain.config.run",
    "load_run_config": "satchain.config.run",
    "predict": "satchain.prediction.core",
    "Predictions": "satchain.prediction.core",
    "compare": "satchain.comparison",
    "Comparison": "satchain.comparison",
    "CheckRow": "satchain.comparison",
    "SystemOTF": "satchain.tf.budget",
    "coltman_ctf": "satchain.tf.ctf",
    "mtf_from_ctf": "satchain.tf.ctf",
    "predict_quality": "satchain.prediction.quality",
    "budget": "satchain.prediction.budget",
    "SystemBudget": "satchain.prediction.budget",
    "simulate": "satchain.engine.simulate",
    "simulate_image": "satchain.engine.degrade",
    "SimulatedImage": "satchain.engine.degrade",
    "simulate_file": "satchain.engine.files",
    "simulate_sweep": "satchain.engine.sweep",
    "load_layout": "satchain.scene",
    "read_truth": "satchain.scene.truth",
    "Truth": "satchain.scene.truth",
    "Rect": "satchain.geometry",
    "measure_edge": "satchain.measure.edge",
    "measure_star": "satchain.measure.star",
    "measure_bars": "satchain.measure.bars",
    "measure_wedge": "satchain.measure.wedge",
    "measure_auto": "satchain.measure.auto",
    "measure_snr": "satchain.measure.snr",
    "measure_registration": "satchain.measure.registration",
    "find_edges": "satchain.measure.find",
    "simulate_bands": "satchain.engine.bands",
    "write_band_rasters": "satchain.engine.bands",
    "BandImages": "satchain.engine.bands",
    "simulate_cube": "satchain.engine.cube",
    "ReflectanceCube": "satchain.engine.cube",
    "simulate_cfa": "satchain.engine.cfa_sim",
    "CFAImages": "satchain.engine.cfa_sim",
    "measure_cfa": "satchain.prediction.cfa",
    "predict_cfa": "satchain.prediction.cfa",
    "simulate_staggered": "satchain.engine.staggered",
    "StaggeredImages": "satchain.engine.staggered",
    "study": "satchain.studies.api",
    "StudyResult": "satchain.studies.api",
    "design": "satchain.studies.api",
    "measure_found_edges": "satchain.measure.find_mtf",
}
#: entry points whose arguments are type-checked on the way in (satchain._argcheck; one-line errors)
_CHECKED = {"simulate", "measure_edge", "measure_star", "measure_bars", "measure_wedge", "measure_auto", "measure_snr",
            "measure_registration",
            "find_edges", "measure_found_edges", "coltman_ctf", "mtf_from_ctf", "load_layout", "read_truth", "compare",
            "load_run_config", "budget"}  # fmt: skip

__all__ = [
    "ConfigError",
    "InputError",
    "ParameterTypeError",
    "ResourceLimitError",
    "SatchainError",
    "SatchainIOError",
    "__version__",
    *sorted(_LAZY),
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'satchain' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    if name in _CHECKED:
        from satchain._argcheck import checked

        value = checked(value)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


if TYPE_CHECKING:  # for type checkers and IDEs: the lazy names, statically
    from satchain.api import RunResult, run  # noqa: F401
    from satchain.comparison import CheckRow, Comparison, compare  # noqa: F401
    from satchain.config.run import RunConfig, Tolerances, load_run_config  # noqa: F401
    from satchain.config.system import ImagingSystem, load_preset, load_system  # noqa: F401
    from satchain.engine.bands import BandImages, simulate_bands, write_band_rasters  # noqa: F401
    from satchain.engine.cfa_sim import CFAImages, simulate_cfa  # noqa: F401
    from satchain.engine.cube import ReflectanceCube, simulate_cube  # noqa: F401
    from satchain.engine.simulate import simulate  # noqa: F401
    from satchain.engine.staggered import StaggeredImages, simulate_staggered  # noqa: F401
    from satchain.geometry import Rect  # noqa: F401
    from satchain.measure.auto import measure_auto  # noqa: F401
    from satchain.measure.bars import measure_bars  # noqa: F401
    from satchain.measure.edge import measure_edge  # noqa: F401
    from satchain.measure.find import find_edges  # noqa: F401
    from satchain.measure.find_mtf import measure_found_edges  # noqa: F401
    from satchain.measure.registration import measure_registration  # noqa: F401
    from satchain.measure.snr import measure_snr  # noqa: F401
    from satchain.measure.star import measure_star  # noqa: F401
    from satchain.measure.wedge import measure_wedge  # noqa: F401
    from satchain.prediction.budget import SystemBudget, budget  # noqa: F401
    from satchain.prediction.cfa import measure_cfa, predict_cfa  # noqa: F401
    from satchain.prediction.core import Predictions, predict  # noqa: F401
    from satchain.prediction.quality import predict_quality  # noqa: F401
    from satchain.scene import load_layout  # noqa: F401
    from satchain.scene.truth import Truth, read_truth  # noqa: F401
    from satchain.studies.api import StudyResult, design, study  # noqa: F401
    from satchain.tf.budget import SystemOTF  # noqa: F401
    from satchain.tf.ctf import coltman_ctf, mtf_from_ctf  # noqa: F401
