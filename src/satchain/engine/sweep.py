"""Parameter sweeps over real imagery: one simulated image per (input, parameters) case, and a manifest.

What pyBSM / nrtk users do for ML robustness tests: degrade each of several images with a camera whose
parameters step through values (``{"motion.smear_px": [0.5, 1, 2]}``: any dotted system key, as
:meth:`ImagingSystem.replace` takes it; several keys form the cartesian product). :func:`simulate_sweep`
validates everything first (keys, values, every system of the product, the inputs, the output names), then
runs :func:`satchain.engine.files.simulate_file` once per case into one directory and keeps
``manifest.json`` / ``manifest.csv`` there up to date (written atomically before the first case and after
each one), so the manifest records what was written even when a case fails or the run is interrupted. The
directory is built as a staging folder beside ``out_dir`` and swapped in as a run folder is
(:func:`satchain.io.runfolder.swap_in`): an earlier sweep's cases are replaced, the user's files kept.

Seeds
-----
Each case gets its own noise seed, :func:`case_seed`: the child of ``numpy.random.SeedSequence(seed)`` whose
spawn key is a hash of the case (the input's file name and the case's parameters) rather than a spawn index.
A case's seed therefore depends only on ``seed``, the input's name and its parameters -- not on the other
cases or their order: running one case alone (one input, one value per key) with the same ``seed``, or
:func:`~satchain.engine.files.simulate_file` on ``system.replace(case.parameters)`` with ``seed=case.seed``,
reproduces its image bit for bit.

Examples
--------
>>> import tempfile
>>> from satchain import load_preset
>>> with tempfile.TemporaryDirectory() as d:
...     cases = simulate_sweep(["paper"], load_preset("ankarasat3"), d, sweep={"motion.smear_px": [0.5, 2]},
...                            scene_pixel_m=2.0, units="reflectance", noise=False)
...     names = sorted(p.name for p in Path(d).iterdir())
>>> [(c.id, c.status, c.shape_px) for c in cases]
[('paper__motion.smear_px=0.5', 'written', (612, 408)), ('paper__motion.smear_px=2', 'written', (612, 408))]
>>> names[:3]
['.satchain-run.json', 'manifest.csv', 'manifest.json']
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import inspect
import io as _io
import itertools
import json
import math
import os
import re
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain._safety import (
    MARKER,
    check_distinct_paths,
    check_output_files,
    check_run_dir,
    check_sidecars,
    write_run_marker,
)
from satchain.errors import ConfigError, SatchainError, SatchainIOError

if TYPE_CHECKING:
    from satchain.config.system import ImagingSystem

__all__ = [
    "MANIFEST_FORMAT",
    "MAX_CASES",
    "Case",
    "case_seed",
    "parse_sweep",
    "plan_sweep",
    "read_manifest",
    "simulate_sweep",
]

#: The ``format`` of ``manifest.json``.
MANIFEST_FORMAT = "satchain-sweep/1"
#: The most cases one sweep may hold (a typo such as ``0:1000`` values should not start a week of work).
MAX_CASES = 10_000
#: Characters kept in output file names; any other becomes ``_``.
_UNSAFE = re.compile(r"[^A-Za-z0-9._=+-]")
#: simulate_file's parameters that the sweep sets itself (per case), never the caller.
_OWN = {"input_", "out", "system", "seed", "focal_plane", "focal_plane_grid", "progress", "notify", "names"}

Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class Case:
    """One case of a sweep: its number ``case`` (from 1), ``id`` (the output's file stem), ``input``, the system
    ``parameters`` it changes, its noise ``seed``, the ``image`` and ``preview`` paths, the image's ``shape_px``
    (None until written), ``status`` (``"planned"``, ``"written"``, ``"failed"``, ``"interrupted"`` or
    ``"not run"``) and the ``error`` of a failed case."""

    case: int
    id: str
    input: str
    parameters: Mapping[str, Any]
    seed: int
    image: Path
    preview: Path
    shape_px: tuple[int, int] | None = None
    status: str = "planned"
    error: str | None = None


# ------------------------------------------------------------------------------------------------ parsing
def _field_kinds(key: str) -> set[str] | None:
    """What the system key takes: a subset of {"number", "bool", "string", "none"}; None for an unknown key
    (:meth:`ImagingSystem.replace` names it)."""
    from satchain.config.system import ImagingSystem

    section, _, field = key.partition(".")
    model = getattr(ImagingSystem.model_fields.get(section), "annotation", None)
    if model is None or not hasattr(model, "model_fields"):
        return None
    if field in ("pitch_m", "fill_factor", "wavelength_m"):  # replace()'s convenience keys
        return {"number"}
    info = model.model_fields.get(field)
    return None if info is None else _kinds(info.annotation)


def _kinds(annotation: Any) -> set[str]:
    if annotation in (float, int):
        return {"number"}
    if annotation is bool:
        return {"bool"}
    if annotation is str or typing.get_origin(annotation) is typing.Literal:
        return {"string"}
    if annotation is type(None):
        return {"none"}
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return set().union(*(_kinds(a) for a in typing.get_args(annotation)))
    return {"other"}  # tuples, dicts, sub-models: not a single value


def _value(key: str, token: str, kinds: set[str] | None, option: str) -> Any:
    """One ``--sweep`` value, typed as the key needs it."""
    t = token.strip()
    low = t.lower()
    kinds = kinds or {"number", "bool", "string"}
    if "none" in kinds and low in ("none", "null"):
        return None
    if "number" in kinds:
        try:
            v = int(t) if re.fullmatch(r"[+-]?\d+", t) else float(t)
        except ValueError:
            v = None
        if v is not None and math.isfinite(v):
            return v
        if kinds <= {"number", "none"}:
            raise ConfigError(f"{option} {key}={t}: not a finite number; {key} takes numbers")
    if "bool" in kinds and low in ("true", "false"):
        return low == "true"
    if kinds <= {"bool", "none"}:
        raise ConfigError(f"{option} {key}={t}: {key} takes true or false")
    if "other" in kinds and not kinds & {"number", "string", "bool"}:
        raise ConfigError(f"{option} {key}: takes a list or table, not one value per case; sweep it in a --system file")
    return t


def parse_sweep(texts: Sequence[str], *, option: str = "--sweep") -> dict[str, list[Any]]:
    """``["KEY=V1,V2,...", ...]`` (the ``--sweep`` options) -> ``{KEY: [values]}``, each value typed as the
    system key needs it: a number, ``true``/``false``, ``none`` for an optional key, or a string
    (``detector.readout=ccd,cmos``). Keys and values are checked here and by :func:`plan_sweep`.

    Examples
    --------
    >>> parse_sweep(["motion.smear_px=0.5,1, 2", "detector.readout=ccd,cmos"])
    {'motion.smear_px': [0.5, 1, 2], 'detector.readout': ['ccd', 'cmos']}
    """
    out: dict[str, list[Any]] = {}
    for text in texts:
        key, eq, rest = str(text).partition("=")
        key = key.strip()
        if not eq or not key:
            raise ConfigError(f"{option} {text!r}: must be KEY=V1,V2,... (e.g. motion.smear_px=0.5,1,2)")
        if key in out:
            raise ConfigError(f"{option} {key}: given twice; give all its values in one {option} {key}=V1,V2,...")
        tokens = rest.split(",")
        if not rest.strip() or any(not t.strip() for t in tokens):
            raise ConfigError(f"{option} {text!r}: needs one or more comma-separated values, none empty")
        kinds = _field_kinds(key)
        out[key] = [_value(key, t, kinds, option) for t in tokens]
    return out


# ------------------------------------------------------------------------------------------------ seeds and names
def case_seed(seed: int, input_: str | os.PathLike, parameters: Mapping[str, Any]) -> int:
    """The noise seed of one case (an integer in [0, 2**32)): the child of ``SeedSequence(seed)`` keyed by a
    SHA-256 hash of the input's file name and the case's parameters (see the module's docstring).

    Examples
    --------
    >>> a = case_seed(0, "data/scene.tif", {"motion.smear_px": 1.0})
    >>> a == case_seed(0, "elsewhere/scene.tif", {"motion.smear_px": 1}), a == case_seed(1, "scene.tif", {})
    (True, False)
    """
    key = json.dumps([Path(str(input_)).name, sorted((k, _canonical(v)) for k, v in parameters.items())])
    words = np.frombuffer(hashlib.sha256(key.encode("utf-8")).digest(), dtype="<u4")
    ss = np.random.SeedSequence(int(seed), spawn_key=tuple(int(w) for w in words))
    return int(ss.generate_state(1, np.uint32)[0])


def _canonical(v: Any) -> Any:
    """A value as the seed and the names see it: 1 and 1.0 are one value."""
    if isinstance(v, (bool, np.bool_)) or v is None or isinstance(v, str):
        return v
    f = float(v)
    return int(f) if f.is_integer() and abs(f) < 2**53 else f


def _text(v: Any) -> str:
    c = _canonical(v)
    if isinstance(c, bool):
        return str(c).lower()
    return "none" if c is None else (repr(c) if isinstance(c, float) else str(c))


def _case_id(input_: str, parameters: Mapping[str, Any]) -> str:
    stem = Path(str(input_)).stem or "input"
    parts = [stem, *(f"{k}={_text(v)}" for k, v in parameters.items())]
    return _UNSAFE.sub("_", "__".join(parts))


# ------------------------------------------------------------------------------------------------ planning
def plan_sweep(
    inputs: Sequence[str | os.PathLike],
    system: ImagingSystem,
    out_dir: str | os.PathLike,
    *,
    sweep: Mapping[str, Sequence[Any]] | None = None,
    seed: int = 0,
    names: Mapping[str, str] | None = None,
) -> tuple[list[Case], list[ImagingSystem]]:
    """The cases of a sweep and their systems, every one validated; nothing is read or written.

    Raises ConfigError naming the option and the value: an empty or repeated value, a key the system does not
    have, a value it refuses (every combination is built), more than :data:`MAX_CASES` cases, or two cases
    whose outputs would have one name.
    """
    name = dict(names or {}).get
    opt, opt_in = name("sweep", "sweep"), name("inputs", "inputs")
    texts = [str(i) for i in inputs]  # the inputs as given (a path as its text)
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"{name('seed', 'seed')} {seed!r}: must be an integer >= 0")
    if not texts:
        raise ConfigError(f"{opt_in}: give one or more inputs")
    sweep = {str(k): list(v) for k, v in (sweep or {}).items()}
    n = len(texts) * math.prod(len(v) for v in sweep.values())
    for key, values in sweep.items():
        if not values:
            raise ConfigError(f"{opt} {key}: needs one or more values")
        canon = [_text(v) for v in values]
        if len(set(canon)) < len(canon):
            dup = next(c for c in canon if canon.count(c) > 1)
            raise ConfigError(f"{opt} {key}: the value {dup} is given twice; each value once")
    if n > MAX_CASES:
        raise ConfigError(f"{opt}: {n} cases (inputs x values); at most {MAX_CASES}: sweep fewer values")
    combos = [dict(zip(sweep, vals, strict=True)) for vals in itertools.product(*sweep.values())]
    systems = [_replaced(system, combo, opt) for combo in combos]
    out = Path(out_dir)
    cases: list[Case] = []
    seen: dict[str, str] = {}
    for input_ in texts:
        for combo in combos:
            cid = _case_id(input_, combo)
            if len(cid) + 4 > 255:
                raise ConfigError(f"{opt}: the output name {cid[:40]!r}... is over 255 characters; sweep fewer keys")
            if cid.lower() in seen:  # also on a case-insensitive file system
                raise ConfigError(
                    f"{opt_in} {seen[cid.lower()]} and {_show(input_, combo)} would both write {cid + '.tif'!r} "
                    "(two inputs of one name, or values that differ only in case or unsafe characters); rename "
                    "an input or change a value"
                )
            seen[cid.lower()] = _show(input_, combo)
            s = int(seed) if (len(texts) == 1 and not sweep) else case_seed(seed, input_, combo)
            cases.append(Case(len(cases) + 1, cid, input_, combo, s, out / f"{cid}.tif", out / f"{cid}.png"))
    return cases, systems * len(texts)


def _show(input_: str, combo: Mapping[str, Any]) -> str:
    return repr(input_) + "".join(f" {k}={_text(v)}" for k, v in combo.items())


def _replaced(system: ImagingSystem, combo: dict[str, Any], opt: str) -> ImagingSystem:
    try:
        return system.replace(combo) if combo else system
    except ConfigError as exc:
        shown = ", ".join(f"{k}={_text(v)}" for k, v in combo.items())
        raise ConfigError(f"{opt} {shown}: {exc}") from None


# ------------------------------------------------------------------------------------------------ running
def simulate_sweep(
    inputs: Sequence[str | os.PathLike],
    system: ImagingSystem,
    out_dir: str | os.PathLike,
    *,
    sweep: Mapping[str, Sequence[Any]] | None = None,
    seed: int = 0,
    progress: Progress | None = None,
    notify: Callable[[str], None] | None = None,
    names: Mapping[str, str] | None = None,
    **options: Any,
) -> list[Case]:
    """Simulate every input under every combination of ``sweep`` values into ``out_dir``, with a manifest.

    Parameters
    ----------
    inputs : sequence of str or path
        Images of reflectance or scenes, as :func:`~satchain.engine.files.simulate_file` takes them.
    system : ImagingSystem
        The camera; each case is ``system.replace(case.parameters)``.
    out_dir : path
        A new or empty directory, or one an earlier sweep wrote (it holds ``.satchain-run.json`` of kind
        ``"simulate"``). Each case writes ``<input stem>__<key>=<value>...tif`` and its ``.png`` preview.
    sweep : mapping, optional
        ``{dotted system key: [values]}``; several keys form the cartesian product (the last varies fastest).
    seed : int
        The sweep's seed; each case's own is :func:`case_seed` (a single input without a sweep keeps ``seed``).
    progress : callable, optional
        ``progress(stage, done, total)``: ``("cases", i, n)`` before each case and after the last, and
        simulate_file's own stages in between.
    notify, names
        As in :func:`~satchain.engine.files.simulate_file` (``names`` also names ``"sweep"`` and ``"inputs"``).
    **options
        simulate_file's other options, the same for every case (``scene_pixel_m``, ``input_scale``,
        ``units``, ``noise``, ``scheduler``, ...).

    Returns
    -------
    list of Case
        Every case ``"written"``, in order (``manifest.json`` holds the same records).

    Raises
    ------
    ConfigError, SatchainIOError
        Before anything is written (see :func:`plan_sweep`; also a bad option, an unreadable input, an output
        directory that is not a sweep's). An error in a case is raised as it is, after the case's files were
        removed and the manifest written (that case ``"failed"``, or ``"interrupted"``; later ones ``"not run"``).
    """
    name = dict(names or {}).get
    _check_options(options, name)
    cases, systems = plan_sweep(inputs, system, out_dir, sweep=sweep, seed=seed, names=names)
    out = Path(out_dir)
    _check_outputs(cases, out, options, names, name, systems)
    header = _header(system, sweep or {}, seed, options)
    with _sweep_staging(out, notify) as stage:  # swapped in for out at the end (also after a failed case)
        write_run_marker(stage, kind="simulate")
        _write_manifest(stage, header, cases)
        _run_cases(cases, systems, stage, header, progress, notify, names, options)
    return cases


def _run_cases(cases: list[Case], systems: list[ImagingSystem], stage: Path, header: dict[str, Any],
               progress: Progress | None, notify, names, options: Mapping[str, Any]) -> None:  # fmt: skip
    """Each case into ``stage`` (its records keep their final paths), the manifest after each one."""
    from satchain.engine.files import simulate_file

    report = progress or (lambda stage, done, total: None)
    for i, (case, sys_i) in enumerate(zip(cases, systems, strict=True)):
        report("cases", i, len(cases))
        try:
            r = simulate_file(case.input, stage / case.image.name, sys_i, seed=case.seed, progress=report,
                              notify=notify, names=names, **options)  # fmt: skip
        except BaseException as exc:
            _remove_case_files(case, stage)
            status = "interrupted" if isinstance(exc, KeyboardInterrupt) else "failed"
            cases[i] = replace(case, status=status, error=_one_line(exc))
            cases[i + 1 :] = [replace(c, status="not run") for c in cases[i + 1 :]]
            _write_manifest(stage, header, cases)
            raise
        shape_px = (r.shape_px[0], r.shape_px[1])
        cases[i] = replace(case, status="written", shape_px=shape_px, preview=case.image.with_suffix(".png"))
        _write_manifest(stage, header, cases)
    report("cases", len(cases), len(cases))


@contextlib.contextmanager
def _sweep_staging(out: Path, notify: Callable[[str], None] | None = None):
    """A staging folder beside ``out`` that replaces it as ``satchain run`` replaces its folder
    (:func:`satchain.io.runfolder.swap_in`: the files satchain did not write are kept, an earlier sweep's
    cases are not), once the manifest is in it: after the last case, or after a failed or interrupted one
    (its manifest says which were written). Before the manifest is written, nothing is changed. The user's files
    kept are named to ``notify``."""
    import shutil
    import tempfile

    from satchain._safety import claim, clean_stale
    from satchain.io.runfolder import swap_in

    out.parent.mkdir(parents=True, exist_ok=True)
    clean_stale(out)  # the staging folders of killed sweeps
    stage = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
    try:
        claim(stage)
        try:
            yield stage
        finally:
            if (stage / "manifest.json").exists():
                kept = swap_in(stage, out)
                if kept and notify is not None:
                    more = f", ... ({len(kept)} in all)" if len(kept) > 5 else ""
                    notify(f"kept {len(kept)} file{'s' * (len(kept) != 1)} satchain did not write in {str(out)!r}: "
                           f"{', '.join(kept[:5])}{more}")  # fmt: skip
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _check_options(options: Mapping[str, Any], name: Callable) -> None:
    from satchain._validate import check_choice
    from satchain.engine.files import simulate_file
    from satchain.engine.sensor import OUTPUT_UNITS

    params = inspect.signature(simulate_file).parameters
    known = set(params) - _OWN
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):  # a wrapper: it checks them itself
        known |= set(options) - _OWN
    if "units" in options:  # the rest simulate_file checks, as every case's input, before it writes anything
        check_choice(name("units", "units"), options["units"], OUTPUT_UNITS)
    if not isinstance(options.get("noise", True), (bool, np.bool_)):
        raise ConfigError(f"{name('noise', 'noise')} = {options['noise']!r}: must be True or False")
    for k in options:
        if k not in known:
            allowed = ", ".join(sorted(known))
            if k in _OWN:
                raise ConfigError(f"{name(k, k)}: set per case by the sweep (or not supported in a sweep)")
            raise ConfigError(f"option {k!r}: simulate_sweep passes on only {allowed}")


def _check_outputs(cases: list[Case], out: Path, options: Mapping[str, Any], names, name: Callable,
                   systems: list[ImagingSystem]) -> None:  # fmt: skip
    """The output directory and every output name, before any work; every input readable, and every case
    checked as simulating it checks it (a GDAL raster: its grid, bands, values; each case's memory, disk and
    valid output; any other input: each case's simulator)."""
    from satchain.engine.files import IMAGE_SUFFIXES, check_case, ground_truth_source
    from satchain.engine.georaster import simulate_raster
    from satchain.io.images import GDAL_SUFFIXES

    opt_out = name("out_dir", name("out", "out_dir"))
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{opt_out} {str(out)!r}: exists and is not a directory; give a directory")
    check_run_dir(out, kind="simulate")
    inputs = {f"{name('inputs', 'inputs')} {c.input!r}": c.input for c in cases if Path(c.input).exists()}
    outputs = {f"{opt_out} (case {c.id})": c.image for c in cases}
    previews = {f"{opt_out} (case {c.id}, preview)": c.preview for c in cases}
    manifests = {f"{opt_out} (manifest)": out / "manifest.json", f"{opt_out} (manifest csv)": out / "manifest.csv"}
    every = {**outputs, **previews, **manifests}
    check_output_files(every)
    for label, path in every.items():  # the names differ by construction; none may be an input
        check_distinct_paths({label: path}, inputs)
    if not (out / MARKER).exists():  # in a sweep's own directory, its files may be replaced
        check_sidecars({**previews, **manifests})
    else:  # but not a file of the user's there (the folder is replaced as a run's: see _sweep_staging)
        from satchain.io.runfolder import check_user_files

        check_user_files(out, {p.name for p in every.values()} | {MARKER})
    raster = {k: options[k] for k in ("band", "scene_pixel_m", "input_scale", "units", "noise") if k in options}
    by_input: dict[str, list[tuple[Case, ImagingSystem]]] = {}
    for c, s in zip(cases, systems, strict=True):
        by_input.setdefault(c.input, []).append((c, s))
    for input_, (first, *others) in by_input.items():
        if Path(input_).suffix.lower() in IMAGE_SUFFIXES and not Path(input_).is_file():
            here = Path(input_)
            what = "is a folder, not a file" if here.is_dir() else "is not a file" if here.exists() else "no such file"
            raise SatchainIOError(f"{name('inputs', 'inputs')} {input_!r}: {what}")
        if Path(input_).suffix.lower() in GDAL_SUFFIXES:
            simulate_raster(input_, first[0].image, first[1], names=names, check_only=True,
                            also_check=[(s, c.image) for c, s in others], **raster)  # fmt: skip
            continue
        src, _ = ground_truth_source(input_, pixel_m=options.get("scene_pixel_m"),
                                     input_scale=options.get("input_scale"), names=names)  # fmt: skip
        for c, s in (first, *others):
            try:
                check_case(s, src, names=names)
            except SatchainError as exc:
                raise type(exc)(f"case {c.id}: {exc}") from None


def _remove_case_files(case: Case, stage: Path) -> None:
    """A failed case leaves nothing under its name: remove what it wrote into ``stage``."""
    for p in (case.image, case.preview):
        with contextlib.suppress(OSError):
            (stage / p.name).unlink()


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    if isinstance(exc, SatchainError) and text:
        return text
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


# ------------------------------------------------------------------------------------------------ the manifest
def _header(system: ImagingSystem, sweep: Mapping[str, Sequence[Any]], seed: int, options: Mapping[str, Any]):
    return {
        "format": MANIFEST_FORMAT,
        "system": system.name,
        "seed": int(seed),
        "seed_rule": "case seed = satchain.engine.sweep.case_seed(seed, input file name, parameters)",
        "sweep": {k: [_canonical(v) for v in vals] for k, vals in sweep.items()},
        "options": {k: (str(v) if isinstance(v, os.PathLike) else v) for k, v in options.items()},
    }


def _record(case: Case, out: Path) -> dict[str, Any]:
    d = asdict(case)
    d["parameters"] = {k: _canonical(v) for k, v in case.parameters.items()}
    d["image"], d["preview"] = case.image.name, case.preview.name  # beside the manifest
    d["shape_px"] = None if case.shape_px is None else list(case.shape_px)
    return d


def _write_manifest(out: Path, header: dict[str, Any], cases: list[Case]) -> None:
    """``manifest.json`` (the header and one record per case) and ``manifest.csv`` (one row per case), each
    written atomically; output paths are file names in the manifest's directory."""
    from satchain.io.images import atomic_path

    records = [_record(c, out) for c in cases]
    done = [n for r in records if r["status"] == "written" for n in (r["image"], r["preview"])]
    files = sorted({*done, MARKER, "manifest.json", "manifest.csv"})  # satchain's (see satchain.io.runfolder)
    text = json.dumps({**header, "files": files, "cases": records}, indent=2, allow_nan=False) + "\n"
    keys = list(header["sweep"])
    buf = _io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["case", "id", "input", *keys, "seed", "status", "image", "preview", "rows", "cols", "error"])
    for r in records:
        shape = r["shape_px"] or ["", ""]
        params = [_text(r["parameters"][k]) for k in keys]
        w.writerow([r["case"], r["id"], r["input"], *params, r["seed"], r["status"], r["image"], r["preview"],
                    *shape, r["error"] or ""])  # fmt: skip
    for fname, content in (("manifest.json", text), ("manifest.csv", buf.getvalue())):
        with atomic_path(out / fname) as tmp:
            tmp.write_text(content, encoding="utf-8")


def read_manifest(out_dir: str | os.PathLike) -> list[Case]:
    """The cases that ``out_dir/manifest.json`` records (paths resolved against ``out_dir``).

    Examples
    --------
    >>> import tempfile
    >>> from satchain import load_preset
    >>> with tempfile.TemporaryDirectory() as d:
    ...     _ = simulate_sweep(["paper"], load_preset("ankarasat3"), d, sweep={"motion.smear_px": [1]},
    ...                        scene_pixel_m=2.0, units="reflectance", noise=False)
    ...     [(c.id, c.status) for c in read_manifest(d)]
    [('paper__motion.smear_px=1', 'written')]
    """
    out = Path(out_dir)
    data = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    if not isinstance(data, dict) or data.get("format") != MANIFEST_FORMAT:
        raise ConfigError(f"{str(out / 'manifest.json')!r}: not a satchain sweep manifest ({MANIFEST_FORMAT})")
    return [
        Case(
            r["case"],
            r["id"],
            r["input"],
            r["parameters"],
            r["seed"],
            out / r["image"],
            out / r["preview"],
            None if r["shape_px"] is None else tuple(r["shape_px"]),
            r["status"],
            r["error"],
        )  # fmt: skip
        for r in data["cases"]
    ]
