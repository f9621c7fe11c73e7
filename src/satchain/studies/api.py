"""The Python entry points of design studies: :func:`study` (``satchain study``) and :func:`design` (``satchain
design``).

>>> import satchain
>>> r = satchain.study("study.toml", "out")                       # doctest: +SKIP
>>> r.passed, r.csv                                              # doctest: +SKIP
>>> d = satchain.design("ankarasat3", {"optics.aperture_diameter_m": (0.2, 1.5)}, ["niirs>=5.2"])  # doctest: +SKIP

A study folder holds ``.satchain-run.json`` (kind "study"), ``study.json`` (what the study is: its base, axes and
settings, their fingerprint, what each axis holds fixed, and how it went), ``study.csv`` / ``study.parquet``
(:mod:`satchain.studies.tables`), ``study.html`` and, at run depth, ``cases/<case>/`` (:mod:`satchain.studies.runner`).
Rerunning the same study into its folder keeps the finished cases; a folder that holds another study is refused.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from satchain.config.study import StudyFile, load_study
from satchain.errors import ConfigError, SatchainIOError
from satchain.studies.cases import Case, expand_cases, held_fixed
from satchain.studies.runner import CaseTask, StudyProgress, execute, fingerprint, finished_record
from satchain.studies.tables import derived

__all__ = ["StudyResult", "design", "study", "study_tasks"]

#: the description of a study folder
STUDY_JSON = "study.json"
Progress = Callable[[StudyProgress], None]


@dataclass(frozen=True)
class StudyResult:
    """What a study produced. ``passed``: no case failed a check or raised. ``rows``: the study table
    (:mod:`satchain.studies.tables`). ``resumed``: cases kept from an earlier run of the same study."""

    out_dir: Path
    depth: str
    n_cases: int
    n_ok: int
    n_failed: int
    n_error: int
    rows: list[dict[str, Any]] = field(repr=False)
    held_fixed: list[str] = field(default_factory=list)
    findings: list[tuple[str, str]] = field(default_factory=list)
    errors: list[tuple[str, str]] = field(default_factory=list)
    resumed: int = 0
    peak_rss_mb: float | None = None

    @property
    def passed(self) -> bool:
        return self.n_failed == 0 and self.n_error == 0

    @property
    def csv(self) -> Path:
        return self.out_dir / "study.csv"

    @property
    def parquet(self) -> Path:
        return self.out_dir / "study.parquet"

    @property
    def page(self) -> Path:
        return self.out_dir / "study.html"


def as_study(study: StudyFile | Mapping[str, Any] | str | Path) -> StudyFile:
    """A StudyFile from a StudyFile, a dict (as in the TOML; relative paths from the current folder) or a path."""
    if isinstance(study, StudyFile):
        return study
    if isinstance(study, Mapping):
        spec = StudyFile.from_dict(dict(study), base_dir=Path.cwd())
        spec.run_config()
        return spec
    return load_study(study)


def _study_fingerprint(spec: StudyFile) -> str:
    s = spec.study
    return fingerprint(
        {
            "base": spec.run_config().absolute().to_dict(),
            "axes": {k: list(v) for k, v in spec.axis_values().items()},
            "depth": s.depth,
            "repeats": s.repeats,
            "zip": s.zip,
        }
    )


def study_tasks(spec: StudyFile, cases: Sequence[Case]) -> list[CaseTask]:
    """The run-depth tasks of ``cases``: one per case x repeat, each with its seed set in its configuration."""
    repeats = spec.study.repeats
    seed_axis = "simulation.seed" in spec.axis_values()
    if seed_axis and repeats > 1:
        raise ConfigError(
            f"[study] repeats = {repeats} with an axis 'simulation.seed': the seeds are the axis' values; "
            "give repeats = 1 or drop the seed axis"
        )
    tasks = []
    for case in cases:
        assert case.config is not None  # depth = "run": expand_cases built it
        base = case.config.absolute()
        for r in range(repeats):
            seed = int(case.values["simulation.seed"]) if seed_axis else case.seeds[r]
            cfg = base.to_dict()
            cfg.setdefault("simulation", {})["seed"] = seed
            folder = f"cases/{case.case_id}" + (f"-r{r + 1}" if repeats > 1 else "")
            fp = fingerprint({"config": cfg, "folder": folder, "format": 1})
            tasks.append(
                CaseTask(case.case_id, r + 1, seed, folder, dict(case.values), cfg, str(base.base_dir),
                         spec.study.reports, fp)  # fmt: skip
            )
    return tasks


def _check_folder(out: Path, fp: str) -> None:
    """``out`` may be missing, empty, or this study's own folder; another study's or a user's is refused."""
    from satchain._safety import check_run_dir

    check_run_dir(out, kind="study")
    try:
        old = json.loads((out / STUDY_JSON).read_text())
    except FileNotFoundError:
        return
    except (OSError, ValueError):
        old = None
    if not isinstance(old, dict) or old.get("fingerprint") != fp:
        raise SatchainIOError(
            f"-o {str(out)!r}: holds another study (its {STUDY_JSON} names a different base, axes or [study] "
            "settings); give a new folder, or remove this one to start again; nothing was changed"
        )


def _rows(tasks: Sequence[CaseTask], records: Mapping[str, dict[str, Any]], cases: Sequence[Case]) -> list[dict]:
    by_id = {c.case_id: c for c in cases}
    budget = {c.case_id: derived(c.system) for c in cases}
    rows: list[dict[str, Any]] = []
    for t in tasks:
        rec = records.get(t.folder)
        if rec is None:
            continue
        common = {
            **by_id[t.case_id].values,
            "case": t.case_id,
            "repeat": t.repeat,
            "seed": t.seed,
            "case_status": rec["status"],
            "message": rec.get("message"),
            **budget[t.case_id],
            "folder": t.folder,
            "report": f"{t.folder}/{rec['report']}" if rec.get("report") else None,
        }
        checks = rec.get("checks") or [{}]
        rows.extend({**common, "figure": None, "kind": None, "check_id": None, "unit": None, **c} for c in checks)
    return rows


def study(
    study: StudyFile | Mapping[str, Any] | str | Path | None,
    out_dir: str | Path,
    *,
    example: str | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    max_cases: int | None = None,
    progress: Progress | None = None,
) -> StudyResult:
    """Run a design study into ``out_dir``: every case validated first, then (run depth) each case through the
    whole chain, then ``study.csv``, ``study.parquet`` and ``study.html``.

    Parameters
    ----------
    study : StudyFile, dict, path or None
        The study file (``satchain schema study``); None with ``example``.
    example : str, optional
        A packaged study instead (``aperture-aberration``: the reference paper's aperture and aberration study).
    workers : int, optional
        Local processes running cases at once (default: the CPUs this process may use, at most the cases).
    scheduler : str, optional
        ``"local"`` (a Dask cluster on this machine, ``workers`` processes) or a Dask scheduler's address; the
        workers must see the study's input files at the same paths.
    max_cases : int, optional
        Allow more than 10,000 cases.
    progress : callable, optional
        ``progress(StudyProgress)`` after each case.

    Raises
    ------
    ConfigError, SatchainIOError
        A bad study or case (naming its case, key and value), a folder that holds something else: nothing written.
    """
    import os

    from satchain._safety import write_run_marker
    from satchain.report._save import write_text
    from satchain.studies.tables import budget_rows, write_tables

    if example is not None:
        if study is not None:
            raise ConfigError("study(): give a study or example=..., not both")
        from satchain.studies.examples import example_path

        study = example_path(example)
    if study is None:
        raise ConfigError("study(): give a study file (a path, a dict or a StudyFile) or example=...")
    if workers is not None and not 1 <= int(workers) <= 1024:
        raise ConfigError(f"--workers = {workers!r}: must be in [1, 1024]")
    spec = as_study(study)
    cases = expand_cases(spec, max_cases=max_cases)  # every case validated before anything is written
    depth = spec.study.depth
    tasks = study_tasks(spec, cases) if depth == "run" else []
    out = Path(out_dir).resolve()
    fp = _study_fingerprint(spec)
    _check_folder(out, fp)
    fixed = held_fixed(spec)
    out.mkdir(parents=True, exist_ok=True)
    write_run_marker(out, kind="study")
    meta: dict[str, Any] = {
        "format": 1,
        "fingerprint": fp,
        "depth": depth,
        "axes": {k: list(v) for k, v in spec.axis_values().items()},
        "repeats": spec.study.repeats,
        "zip": spec.study.zip,
        "reports": spec.study.reports,
        "held_fixed": fixed,
        "base": spec.run_config().absolute().to_dict(),
        "cases": [{"case": c.case_id, "values": c.values, "seeds": list(c.seeds)} for c in cases],
        "complete": False,
    }
    write_text(out / STUDY_JSON, json.dumps(meta, indent=1, default=str))

    records: dict[str, dict[str, Any]] = {}
    resumed = 0
    if tasks:
        from satchain._safety import clean_stale

        clean_stale(out / "cases" / "_")  # staging folders of workers that were killed
        for t in tasks:
            rec = finished_record(out, t)
            if rec is not None:
                records[t.folder] = rec
        resumed = len(records)
        pending = [t for t in tasks if t.folder not in records]
        counts = {"done": 0, "failed": 0}
        for rec in records.values():
            counts["done" if rec["status"] == "ok" else "failed"] += 1

        def done(task: CaseTask, record: dict[str, Any]) -> None:
            records[task.folder] = record
            counts["done" if record["status"] == "ok" else "failed"] += 1
            if progress is not None:
                progress(StudyProgress(counts["done"], counts["failed"], len(tasks), task.case_id, record["status"]))

        if progress is not None:
            progress(StudyProgress(counts["done"], counts["failed"], len(tasks), "", "resumed"))
        cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        n = int(workers) if workers is not None else max(1, min(cpus, len(pending)))
        from satchain._safety import terminate_as_interrupt

        try:
            with terminate_as_interrupt() as received:  # SIGTERM as Ctrl-C: the workers stopped, finished cases kept
                execute(pending, out, workers=n, scheduler=scheduler, done=done)
                received.check()
        except BaseException:
            clean_stale(out / "cases" / "_")  # the stopped workers' staging folders
            raise
        rows = _rows(tasks, records, cases)
    else:
        rows = budget_rows(cases)

    statuses = [r["status"] for r in records.values()]
    errors = sorted((t.folder, records[t.folder]["message"]) for t in tasks if records[t.folder]["status"] == "error")
    from satchain.studies.examples import aperture_findings

    findings = aperture_findings(rows, spec.axis_values())
    write_tables(out, list(spec.axis_values()), rows)
    _write_page(out, rows, spec, fixed, findings)
    rss = [r["peak_rss_mb"] for r in records.values() if r.get("peak_rss_mb") is not None]
    result = StudyResult(
        out, depth, len(tasks) or len(cases), statuses.count("ok") if tasks else len(cases), statuses.count("failed"),
        statuses.count("error"), rows, fixed, findings, errors, resumed, max(rss) if rss else None,
    )  # fmt: skip
    meta.update(complete=True, n_ok=result.n_ok, n_failed=result.n_failed, n_error=result.n_error,
                peak_rss_mb_per_worker=result.peak_rss_mb, findings=[list(f) for f in findings])  # fmt: skip
    write_text(out / STUDY_JSON, json.dumps(meta, indent=1, default=str))
    return result


def _write_page(out: Path, rows: list[dict[str, Any]], spec: StudyFile, fixed: list[str], findings: list) -> None:
    from satchain.report.study_page import write_study_page

    write_study_page(out / "study.html", rows, axes=spec.axis_values(), depth=spec.study.depth, held_fixed=fixed,
                     findings=findings, title=f"satchain study: {out.name}")  # fmt: skip


def design(
    system: Any,
    vary: Mapping[str, tuple[float, float]],
    targets: Sequence[str | Any],
    *,
    grid: int = 21,
) -> Any:
    """The inverse question by the budget (``satchain design``): with one key in ``vary``, the ranges of it in
    ``[lo, hi]`` that meet every target (:class:`~satchain.studies.design.DesignResult`, by root finding); with
    two, the feasibility map on a ``grid x grid`` grid (:class:`~satchain.studies.design_map.FeasibilityMap`).

    ``system``: an ImagingSystem, a preset name or a system file; ``targets``: ``"niirs>=5.2"`` strings (or
    :class:`~satchain.studies.design.Target`).
    """
    from satchain.config.system import ImagingSystem, load_system
    from satchain.studies.design import Target, parse_target
    from satchain.studies.design import design as run_design

    sys_ = system if isinstance(system, ImagingSystem) else load_system(system)
    parsed = [t if isinstance(t, Target) else parse_target(str(t)) for t in targets]
    if not isinstance(vary, Mapping) or not 1 <= len(vary) <= 2:
        raise ConfigError(f"design(): vary = {vary!r}: must map one or two keys to (lo, hi)")
    ranges = []
    for key, span in vary.items():
        try:
            lo, hi = (float(v) for v in span)
        except (TypeError, ValueError):
            raise ConfigError(f"design(): vary[{key!r}] = {span!r}: must be (lo, hi), two numbers") from None
        if not lo < hi:
            raise ConfigError(f"design(): vary[{key!r}] = {span!r}: lo must be below hi")
        ranges.append((key, lo, hi))
    if len(ranges) == 1:
        return run_design(sys_, *ranges[0], parsed)
    from satchain.studies.design_map import feasibility_map

    return feasibility_map(sys_, ranges, parsed, n=grid)
