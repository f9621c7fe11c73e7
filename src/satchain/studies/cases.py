"""The cases of a study: its axes expanded (cartesian product, or zipped), each case named, seeded and validated.

:func:`expand_cases` builds every case's system before any case runs, through
:func:`satchain.studies.design.vary_system` (which states what a variation holds fixed: varying the aperture holds
the focal length), so a bad value is refused naming its case, key and the allowed range. The study table is
:mod:`satchain.studies.tables`; running the cases, :mod:`satchain.studies.runner` and
:func:`satchain.studies.api.study`.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from satchain.config.run import RunConfig
from satchain.config.study import StudyFile
from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError

__all__ = ["MAX_CASES", "Case", "case_seeds", "expand_cases", "held_fixed"]

#: more cases than this are refused unless ``max_cases`` allows them
MAX_CASES = 10_000

#: keys a case may vary at depth = "run" only (they change the simulation, not the predicted budget)
_RUN_ONLY = ("scene.pixel_m", "simulation.seed")


def _run_only(key: str) -> bool:
    return key in _RUN_ONLY or key.startswith("as_built.")


@dataclass(frozen=True)
class Case:
    """One case: its id (``c0001``), its axes' values, a seed per repeat, and its system (validated)."""

    case_id: str
    index: int
    values: dict[str, float]
    seeds: tuple[int, ...]
    system: ImagingSystem = field(compare=False, repr=False)
    #: at depth = "run": the case's run configuration (its system inline, its run-only keys set), validated
    config: RunConfig | None = field(default=None, compare=False, repr=False)


def case_seeds(base_seed: int, index: int, repeats: int) -> tuple[int, ...]:
    """The seeds of case ``index``'s repeats, derived from the base seed: distinct per case and repeat, and the
    same on every expansion of the same study.

    Examples
    --------
    >>> case_seeds(7, 0, 2) == case_seeds(7, 0, 2)
    True
    >>> len(set(case_seeds(7, 0, 2) + case_seeds(7, 1, 2)))
    4
    """
    return tuple(
        int(np.random.SeedSequence(int(base_seed), spawn_key=(index, r)).generate_state(1, dtype=np.uint32)[0])
        for r in range(repeats)
    )


def _combinations(study: StudyFile) -> list[tuple[float, ...]]:
    axes = study.axis_values()
    lists = list(axes.values())
    if study.study.zip:
        lengths = {k: len(v) for k, v in axes.items()}
        first = next(iter(lengths))
        for k, n in lengths.items():
            if n != lengths[first]:
                raise ConfigError(
                    f"zip = true: axis {first!r} has {lengths[first]} values but axis {k!r} has {n}; zipped axes "
                    "need equal lengths"
                )
        return list(zip(*lists, strict=True))
    return list(itertools.product(*lists))


def _count(study: StudyFile) -> int:
    lengths = [len(v) for v in study.axis_values().values()]
    return lengths[0] if study.study.zip else math.prod(lengths)


def expand_cases(study: StudyFile, *, max_cases: int | None = None, base: RunConfig | None = None) -> list[Case]:
    """Every case of ``study``, each validated (its system built) before any runs.

    Raises
    ------
    ConfigError
        Mismatched lengths with ``zip = true`` (naming both axes), more than ``max_cases`` cases (default
        :data:`MAX_CASES`), a key that a budget-depth study cannot vary, or a value out of range (naming the
        case, the key and the value).
    """
    limit = MAX_CASES if max_cases is None else int(max_cases)
    depth = study.study.depth
    for key in study.axis_values():
        if _run_only(key) and depth != "run":
            raise ConfigError(
                f"axis {key!r}: varies the simulation, not the predicted budget; it is allowed at depth = 'run' "
                f"only (this study has depth = {depth!r})"
            )
    combos = _combinations(study)  # mismatched zip lengths first
    n = _count(study)
    if n > limit:
        raise ConfigError(
            f"the study has {n} cases, more than {limit}"
            + (f"; allow them with --max-cases {n} (max_cases={n})" if max_cases is None else "")
        )
    config = study.run_config() if base is None else base
    design = config.load_system()
    width = max(4, len(str(n)))
    keys = list(study.axis_values())
    cases = []
    for i, combo in enumerate(combos):
        cid = f"c{i + 1:0{width}d}"
        values = dict(zip(keys, combo, strict=True))
        system = _case_system(design, values, cid)
        run = _case_config(config, system, values, cid) if depth == "run" else None
        cases.append(Case(cid, i, values, case_seeds(config.simulation.seed, i, study.study.repeats), system, run))
    return cases


def _case_config(config: RunConfig, system: ImagingSystem, values: dict[str, float], cid: str) -> RunConfig:
    """The run configuration of a case at depth = "run": the base's, with the case's system inline and its
    run-only keys (``as_built.<section>.<key>``, ``scene.pixel_m``, ``simulation.seed``) set; validated, the
    camera as built included."""
    d = config.absolute().to_dict()
    d["system"] = {"inline": system.to_dict()}
    where = []
    for key, value in values.items():
        if not _run_only(key):
            continue
        where.append(f"{key} = {value:g}")
        *path, last = key.split(".")
        node = d
        for part in path:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise ConfigError(f"case {cid}: {key}: {part} is not a table of keys")
        node[last] = int(value) if key == "simulation.seed" and float(value).is_integer() else value
    try:
        run = RunConfig.from_dict(d, base_dir=config.base_dir)
        run.load_as_built_system(system)
    except ConfigError as exc:
        raise ConfigError(f"case {cid} ({', '.join(where) or 'its system'}): {exc}") from None
    return run


def _case_system(design: ImagingSystem, values: dict[str, float], cid: str) -> ImagingSystem:
    from satchain.studies.design import vary_system

    system = design
    for key, value in values.items():
        if _run_only(key):
            continue  # validated with the run configuration at depth = "run"
        try:
            system = vary_system(system, key, value)
        except ConfigError as exc:
            raise ConfigError(f"case {cid} ({key} = {value:g}): {exc}") from None
    return system


def held_fixed(study: StudyFile, base: RunConfig | None = None) -> list[str]:
    """One sentence per axis: what varying its key holds fixed, and the key that follows it."""
    from satchain.studies.design import fixed_and_following

    design = (study.run_config() if base is None else base).load_system()
    lines = []
    for key in study.axis_values():
        if _run_only(key):
            lines.append(f"{key}: the system held fixed")
            continue
        fixed, follows = fixed_and_following(design, key)
        lines.append(f"{key}: {fixed}" + (f"; {follows} follows" if follows else ""))
    return lines
