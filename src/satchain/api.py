"""The notebook entry point: :func:`run` and the typed results that the stages of a run hand each other.

>>> import satchain
>>> result = satchain.run({"scene": {"layout": "my_scene.toml"}})       # doctest: +SKIP
>>> result.passed, result.simulation.image.shape                        # doctest: +SKIP
>>> [(r.figure, r.measured, r.predicted, r.passed) for r in result.comparison.rows]  # doctest: +SKIP

Stages: budget (prediction of MTF, CTF, radiometry, SNR, GIQE) -> scene (ground truth and its truth record) ->
simulation (the satellite image and the focal-plane image, in memory) -> measurement (every target, and the
SNR) -> prediction of what each measurement should give -> comparison. Nothing is written unless ``out_dir``
is given (``satchain run`` gives it): then the run directory (report.html, results.json, images, figures,
manifest.json) is written atomically, see :mod:`satchain.pipeline`. The result types live in
:mod:`satchain.results` (re-exported here).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from satchain.config.run import RunConfig
from satchain.results import (
    NULL_MEANING,
    RESULTS_FORMAT_VERSION,
    BudgetResult,
    Measurements,
    RunResult,
    SceneResult,
    SimulationResult,
    strict_json,
)

__all__ = [
    "NULL_MEANING",
    "RESULTS_FORMAT_VERSION",
    "BudgetResult",
    "Measurements",
    "RunResult",
    "SceneResult",
    "SimulationResult",
    "as_run_config",
    "run",
    "strict_json",
]

Progress = Callable[[str, int, int], None]


def as_run_config(config: RunConfig | Mapping[str, Any] | str | Path | None) -> RunConfig:
    """A RunConfig from a RunConfig, a dict (as in the TOML), a TOML path, or None (the defaults)."""
    import os

    from satchain.config.run import load_run_config
    from satchain.errors import ParameterTypeError

    if isinstance(config, RunConfig):
        return config
    if isinstance(config, Mapping):
        return RunConfig.from_dict(dict(config))
    if config is not None and not isinstance(config, (str, Path, os.PathLike)):
        shown = repr(config) if len(repr(config)) <= 60 else repr(config)[:57] + "..."
        raise ParameterTypeError(
            f"run(): config = {shown}: must be a RunConfig, a dict (as in the TOML), a TOML path or None"
        )
    return load_run_config(config)


from satchain._argcheck import checked  # noqa: E402  (here, beside its one use: the types above stay apart)


@checked
def run(
    config: RunConfig | Mapping[str, Any] | str | Path | None = None,
    *,
    out_dir: str | Path | None = None,
    progress: Progress | None = None,
) -> RunResult:
    """Predict, simulate, measure and compare; write the run directory only when ``out_dir`` is given.

    Parameters
    ----------
    config : RunConfig, dict, path or None
        The run configuration (``satchain run --print-config`` shows every key); None: the defaults (the
        reference paper's camera and scene, which takes a minute or two).
    out_dir : path, optional
        Write report.html, results.json, images, figures and manifest.json there (replaced atomically; an
        existing directory must be a satchain run directory; its files that satchain did not write are kept,
        ``RunResult.kept_files``).
    progress : callable, optional
        ``progress(stage, done, total)``, stage one of :data:`satchain.pipeline.STAGES`.

    Returns
    -------
    RunResult
    """
    from satchain import pipeline

    cfg = as_run_config(config)
    if out_dir is None:
        return pipeline.run_in_memory(cfg, progress=progress)
    return pipeline.run_to_directory(cfg, out_dir, progress=progress)
