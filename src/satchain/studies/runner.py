"""The cases of a run-depth study, each run through the whole chain in a worker, each into its own folder.

A case (one case x one repeat) is a :class:`CaseTask`: picklable, with its run configuration as a dict (absolute
paths: each worker reads its own inputs). :func:`run_case` runs it in a worker (a local process or a Dask worker)
and writes ``DIR/cases/<case>/`` atomically (staging folder, then a rename): ``results.json``, ``summary.csv``,
``config.toml`` (``satchain run --config`` on it reproduces the case), ``case.json`` (its record: status, checks,
time, peak memory) and, as ``[study] reports`` asks, ``report.html`` with its figures. A case that raises is
recorded (``status = "error"`` and its one-line message); the study goes on.

:func:`execute` runs the cases not finished yet (a finished case is one whose ``case.json`` carries the task's
fingerprint: a rerun keeps it), on ``workers`` local processes or on a Dask cluster, and calls ``progress`` as
each ends. Interrupted (Ctrl-C, SIGTERM) it stops the workers and re-raises; every finished case is kept. A local
worker that dies (killed, out of memory) breaks the pool: the cases it may have been running are tried once more
on a fresh pool, then recorded as errors.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

__all__ = [
    "CASE_RECORD",
    "CaseTask",
    "StudyProgress",
    "execute",
    "finished_record",
    "fingerprint",
    "run_case",
]

#: the record of a finished case, in its folder
CASE_RECORD = "case.json"
#: how long to wait for a Dask scheduler named by its address (s)
CONNECT_TIMEOUT_S = 10
#: how many times a case whose worker died is tried before it is recorded as an error
_TRIES = 2


def fingerprint(data: Any) -> str:
    """A stable hash of JSON-able ``data`` (sorted keys)."""
    text = json.dumps(data, sort_keys=True, default=str, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:20]


@dataclass(frozen=True)
class CaseTask:
    """One case x repeat of a run-depth study: what a worker needs to run it and write its folder."""

    case_id: str
    repeat: int
    seed: int
    folder: str  # relative to the study folder: cases/c0001 (cases/c0001-r2 with repeats)
    values: dict[str, float]
    config: dict[str, Any]  # the case's run configuration (absolute paths), its seed set
    base_dir: str
    reports: str  # none | failed | all
    fingerprint: str


class StudyProgress(NamedTuple):
    """Where a study stands after a case ended: cases done (ok or failed a check), failed (a check failed or the
    case raised), their total, the case that ended and its status."""

    done: int
    failed: int
    total: int
    case: str
    status: str


def _peak_rss_mb() -> float | None:
    try:
        import resource
    except ImportError:  # pragma: no cover (not on Windows)
        return None
    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return round(kb / 1024.0 if os.uname().sysname != "Darwin" else kb / 2**20, 1)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    from satchain.errors import SatchainError

    return text if isinstance(exc, SatchainError) else f"{type(exc).__name__}: {text}"


def _check(row: Any) -> dict[str, Any]:
    from satchain.report.summary_csv import UNITS

    return {
        "figure": row.figure,
        "kind": row.kind,
        "check_id": row.id,
        "unit": UNITS.get(row.kind, ("", ""))[0],
        "measured": row.measured,
        "predicted": row.predicted,
        "error": row.error,
        "sigma": row.sigma,
        "z": row.z,
        "pass": row.passed,
    }


def run_case(task: CaseTask, out_dir: str) -> dict[str, Any]:
    """Run one case through the whole chain and write its folder under ``out_dir`` (atomically); return its
    record (also written as ``case.json``). An exception of the case is recorded, not raised; an interruption
    (KeyboardInterrupt) is raised, and the case's staging folder removed."""
    from satchain import pipeline
    from satchain._safety import claim, write_run_marker
    from satchain.config.run import RunConfig, config_to_toml
    from satchain.io.runfolder import swap_in
    from satchain.report._save import write_text
    from satchain.results import strict_json

    final = Path(out_dir) / task.folder
    final.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{final.name}.staging-", dir=final.parent))
    t0 = time.perf_counter()
    record: dict[str, Any] = {
        "format": 1,
        "case": task.case_id,
        "repeat": task.repeat,
        "seed": task.seed,
        "values": task.values,
        "fingerprint": task.fingerprint,
    }
    try:
        claim(staging)
        write_run_marker(staging)
        try:
            config = RunConfig.from_dict(task.config, base_dir=task.base_dir)
            write_text(staging / "config.toml", config_to_toml(config))
            result = pipeline.run_in_memory(config)
            passed = result.passed
            keep = task.reports == "all" or (task.reports == "failed" and passed is False)
            if keep:
                from satchain.report._jobs import FigureJobs

                pipeline.write_run_directory(result, staging, jobs=FigureJobs(0))  # no helpers inside a worker
            else:
                from satchain.report.summary_csv import write_summary_csv

                results = result.to_json_dict()
                write_text(staging / "results.json", json.dumps(results, indent=1, allow_nan=False))
                write_summary_csv(results, staging / "summary.csv")
            checks = [_check(r) for r in result.comparison.rows]
            record.update(
                status="failed" if passed is False else "ok",
                message=None,
                n_checked=result.comparison.n_checked,
                n_failed=result.comparison.n_failed,
                report="report.html" if keep else None,
                checks=checks,
            )
        except Exception as exc:  # the case's error is its result; the study goes on
            record.update(status="error", message=_one_line(exc), n_checked=0, n_failed=0, report=None, checks=[])
        record.update(elapsed_s=round(time.perf_counter() - t0, 3), peak_rss_mb=_peak_rss_mb())
        record = strict_json(record)
        write_text(staging / CASE_RECORD, json.dumps(record, indent=1, allow_nan=False))
        swap_in(staging, final)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return record


def finished_record(out: Path, task: CaseTask) -> dict[str, Any] | None:
    """The record of ``task`` when its folder holds one of this very task (same fingerprint) that finished (ok
    or failed a check; an error is run again); else None."""
    try:
        data = json.loads((out / task.folder / CASE_RECORD).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("fingerprint") != task.fingerprint:
        return None
    return data if data.get("status") in ("ok", "failed") else None


def _error_record(task: CaseTask, message: str) -> dict[str, Any]:
    return {
        "format": 1, "case": task.case_id, "repeat": task.repeat, "seed": task.seed, "values": task.values,
        "fingerprint": task.fingerprint, "status": "error", "message": message, "n_checked": 0, "n_failed": 0,
        "report": None, "checks": [], "elapsed_s": None, "peak_rss_mb": None,
    }  # fmt: skip


def _worker_init() -> None:  # the parent decides about Ctrl-C; a worker goes on until told to stop
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


Done = Callable[[CaseTask, dict[str, Any]], None]


def execute(
    tasks: Sequence[CaseTask], out: Path, *, workers: int = 1, scheduler: str | None = None, done: Done
) -> None:
    """Run ``tasks`` (not finished yet) and call ``done(task, record)`` as each ends; on local processes
    (``workers``; 1: in this process), or on a Dask cluster (``scheduler``: "local", or a scheduler's address)."""
    if not tasks:
        return
    if scheduler is not None:
        _execute_dask(tasks, out, workers=workers, scheduler=scheduler, done=done)
    elif workers <= 1:
        for task in tasks:
            done(task, run_case(task, str(out)))
    else:
        _execute_local(tasks, out, workers=workers, done=done)


def _execute_local(tasks: Sequence[CaseTask], out: Path, *, workers: int, done: Done) -> None:
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    todo = list(tasks)
    tries: dict[str, int] = {}
    ctx = multiprocessing.get_context("spawn")  # a clean interpreter: no threads or locks of this one
    while todo:
        pool = ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=ctx, initializer=_worker_init)
        running: dict[Future, CaseTask] = {}
        broken = False
        try:
            while (todo or running) and not broken:
                while todo and len(running) < workers:  # never more submitted than can run: a break is theirs
                    task = todo.pop(0)
                    running[pool.submit(run_case, task, str(out))] = task
                finished, _ = wait(running, return_when=FIRST_COMPLETED)
                for fut in finished:
                    task = running.pop(fut)
                    try:
                        done(task, fut.result())
                    except BrokenProcessPool:
                        broken = True
                        running[fut] = task  # handled below with the others that were running
            if broken:
                for task in running.values():
                    record = finished_record(out, task)
                    if record is not None:
                        done(task, record)
                        continue
                    tries[task.folder] = tries.get(task.folder, 1) + 1
                    if tries[task.folder] > _TRIES:
                        msg = f"its worker process died (killed, or out of memory) in {_TRIES} tries"
                        done(task, _write_error(out, task, msg))
                    else:
                        todo.insert(0, task)
        except BaseException:
            _stop(pool)
            raise
        pool.shutdown(wait=True)
        if broken:  # the dead workers' staging folders (their processes are gone now)
            from satchain._safety import clean_stale

            clean_stale(out / "cases" / "_")


def _stop(pool: Any) -> None:
    """Stop a process pool now: pending cases cancelled, running workers terminated (their staging folders are
    removed by the next run of the study)."""
    procs = list(getattr(pool, "_processes", {}).values())  # the stdlib has no public way before 3.14
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        with contextlib.suppress(Exception):
            p.terminate()
    for p in procs:
        with contextlib.suppress(Exception):
            p.join(5)


def _write_error(out: Path, task: CaseTask, message: str) -> dict[str, Any]:
    """Record a case that could not run in its folder (``case.json`` only) and return the record."""
    from satchain.io.images import atomic_path

    record = _error_record(task, message)
    folder = out / task.folder
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_path(folder / CASE_RECORD) as tmp:
        Path(tmp).write_text(json.dumps(record, indent=1))
    return record


def _execute_dask(tasks: Sequence[CaseTask], out: Path, *, workers: int, scheduler: str, done: Done) -> None:
    try:
        import distributed
    except ImportError:
        from satchain.errors import ConfigError

        raise ConfigError(
            f"--scheduler {scheduler!r}: needs dask.distributed, which is not installed; "
            "install it with: python -m pip install 'satchain[dask]'"
        ) from None
    cluster = None
    if scheduler == "local":
        cluster = distributed.LocalCluster(
            n_workers=max(1, workers), threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = distributed.Client(cluster)
    else:
        try:
            client = distributed.Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s")
        except (OSError, TimeoutError, ValueError) as exc:
            from satchain.errors import SatchainIOError

            raise SatchainIOError(f"--scheduler {scheduler!r}: cannot reach the Dask scheduler: {exc}") from None
    futures = {}
    try:
        for task in tasks:
            futures[client.submit(run_case, task, str(out), pure=False, key=f"satchain-case-{task.folder}")] = task
        for fut in distributed.as_completed(list(futures)):
            task = futures[fut]
            try:
                record = fut.result()
            except Exception as exc:  # a worker lost (KilledWorker) or a task that could not run there
                record = finished_record(out, task) or _write_error(out, task, _one_line(exc))
            done(task, record)
    except BaseException:
        with contextlib.suppress(Exception):
            client.cancel(list(futures), force=True)
        raise
    finally:
        with contextlib.suppress(Exception):
            client.close()
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close()
