"""Data safety: never overwrite an input, replace only satchain's own run directories, refuse work that
cannot fit in memory (or on disk) before allocating, and clean what a killed run left behind.

* :func:`check_distinct_paths` -- every output path differs from every input and from the other outputs
  (resolved paths, symbolic links and hard links included).
* :func:`check_run_dir` / :func:`write_run_marker` -- a run directory carries ``.satchain-run.json``
  (``{"tool": "satchain", "kind": "run", "format": 1}``); only a directory holding that marker, an empty
  directory or a missing one may be replaced by ``satchain run``.
* :func:`claim` / :func:`clean_stale` -- staging folders and temporary files carry the id of the process
  that owns them; the next run removes those whose process is gone (never one a live process owns).
* :func:`terminate_as_interrupt` -- while a run writes, SIGTERM raises :class:`Interrupted` (a
  ``KeyboardInterrupt``) like Ctrl-C does, so the staging folder is removed and the previous results kept.
* :func:`check_memory` / :func:`check_disk` -- the need in GiB against a limit: ``SATCHAIN_MEMORY_LIMIT``
  (bytes, or with a K/M/G/T suffix) or 80 % of the memory available now.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import socket
import sys
import threading
import time
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

from satchain.errors import ConfigError, ResourceLimitError, SatchainIOError

__all__ = [
    "MARKER",
    "OWNER",
    "Interrupted",
    "check_disk",
    "check_distinct_paths",
    "check_memory",
    "check_run_dir",
    "check_sidecars",
    "check_star_radius",
    "check_dir_outputs",
    "check_input_file",
    "check_inputs_outside",
    "check_output_files",
    "claim",
    "clean_stale",
    "clean_stale_temp_files",
    "memory_limit_bytes",
    "not_utf8",
    "nothing_measured",
    "terminate_as_interrupt",
    "write_run_marker",
]

#: the file that marks a directory as a satchain run (and the only licence to replace it)
MARKER = ".satchain-run.json"
MARKER_CONTENT = {"tool": "satchain", "kind": "run", "format": 1}
#: the owner file of a staging / old-results folder: which process (on which host) may still use it
OWNER = ".satchain-owner.json"


# ---------------------------------------------------------------------------------------------- paths
def _same(a: Path, b: Path) -> bool:
    if a.resolve() == b.resolve():
        return True
    with contextlib.suppress(OSError):
        return a.exists() and b.exists() and os.path.samefile(a, b)
    return False


def check_distinct_paths(
    outputs: Mapping[str, str | os.PathLike | None], inputs: Mapping[str, str | os.PathLike | None] | None = None
) -> None:
    """Refuse an output that is (or links to) an input or another output.

    Parameters
    ----------
    outputs, inputs : option name (e.g. ``"-o"``, ``"--focal-plane"``, ``"IMAGE"``) -> path (``None`` = not given)

    Raises
    ------
    ConfigError naming both options and the path; nothing has been written.

    Examples
    --------
    >>> check_distinct_paths({"-o": "b.tif"}, inputs={"INPUT": "a.tif"})
    >>> try:
    ...     check_distinct_paths({"-o": "a.tif"}, inputs={"INPUT": "./a.tif"})
    ... except ConfigError as exc:
    ...     print(str(exc)[:48])
    -o 'a.tif' is the same file as INPUT 'a.tif': it
    """
    outs = [(k, Path(v)) for k, v in outputs.items() if v is not None]
    ins = [(k, Path(v)) for k, v in (inputs or {}).items() if v is not None]
    for i, (name, path) in enumerate(outs):
        for other, opath in ins + outs[:i]:
            if _same(path, opath):
                raise ConfigError(
                    f"{name} {str(path)!r} is the same file as {other} {str(opath)!r}: it would be overwritten; "
                    "choose another output path"
                )


# ---------------------------------------------------------------------------------------------- run directories
def write_run_marker(directory: str | os.PathLike, *, kind: str = "run") -> Path:
    """Write the marker into ``directory`` (which satchain has just created, or found empty): ``kind`` is
    ``"run"`` (``satchain run``) or ``"budget"`` (``satchain budget -o``)."""
    path = Path(directory) / MARKER
    path.write_text(json.dumps({**MARKER_CONTENT, "kind": kind}) + "\n")
    return path


def _is_marked(directory: Path, kind: str = "run") -> bool:
    try:
        data = json.loads((directory / MARKER).read_text())
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and data.get("tool") == "satchain" and data.get("kind") == kind


def check_run_dir(out: str | os.PathLike, *, kind: str = "run") -> None:
    """Allow ``out`` to be replaced (``kind="run"``) or written into (``kind="budget"``) only when missing,
    empty, or marked as satchain's output of that kind.

    Raises
    ------
    SatchainIOError naming a few of the entries found; nothing is changed.
    """
    out = Path(out)
    if not out.exists() and not out.is_symlink():
        return
    if out.is_symlink() or not out.is_dir():
        raise SatchainIOError(
            f"-o {str(out)!r}: exists and is not a directory; choose a new or empty directory, nothing was changed"
        )
    entries = sorted(p.name for p in out.iterdir())
    if not entries or _is_marked(out, kind):
        return
    shown = ", ".join(entries[:5]) + (f", ... ({len(entries)} entries)" if len(entries) > 5 else "")
    other = _marked_kind(out)
    why = (f"its {MARKER} marks it as satchain's {other!r} output" if other is not None
           else f"no {MARKER} of satchain's" if MARKER in entries else f"no {MARKER}")  # fmt: skip
    raise SatchainIOError(
        f"-o {str(out)!r}: not a satchain {kind} directory ({why}; it holds {shown}); "
        "choose a new or empty directory, nothing was changed"
    )


def _marked_kind(directory: Path) -> str | None:
    """The ``kind`` satchain's marker in ``directory`` names (None without a readable one)."""
    try:
        data = json.loads((directory / MARKER).read_text())
    except (OSError, ValueError):
        return None
    ok = isinstance(data, dict) and data.get("tool") == "satchain" and isinstance(data.get("kind"), str)
    return data["kind"] if ok else None


# ---------------------------------------------------------------------------------------------- ownership
def claim(directory: str | os.PathLike) -> None:
    """Record the current process as the owner of ``directory`` (a staging or old-results folder)."""
    data = {"pid": os.getpid(), "host": socket.gethostname(), "time": time.time()}
    (Path(directory) / OWNER).write_text(json.dumps(data) + "\n")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # exists (owned by another user) or unknown: keep it
    return True


def _owner_gone(directory: Path, *, min_age_s: float | None) -> bool:
    """True when ``directory``'s owner file names a process of this host that no longer runs; without an owner
    file (killed before claiming), when it is empty and older than ``min_age_s`` (never, if that is None)."""
    try:
        data = json.loads((directory / OWNER).read_text())
        pid, host = int(data["pid"]), str(data["host"])
    except (OSError, ValueError, KeyError, TypeError):
        try:
            return (
                min_age_s is not None
                and not any(directory.iterdir())
                and time.time() - directory.stat().st_mtime > min_age_s
            )
        except OSError:
            return False
    return host == socket.gethostname() and not _alive(pid)


def clean_stale(out: str | os.PathLike, *, min_age_s: float = 60.0) -> list[Path]:
    """Remove the staging folders (``.NAME.staging-*``) and old-results folders (``.NAME.old-*``) in the parent of
    ``out`` whose owning process is gone, for ``out``'s name and for any other run's.

    Another name's folder is touched only when its owner file (pid and host) proves it satchain's and its process
    dead; a folder owned by a live process, or by another host, is kept. An old-results folder whose run died
    between the two renames of the swap (``NAME`` missing) is renamed back to ``NAME``, never removed.
    Returns the folders removed or restored.
    """
    out = Path(out)
    removed: list[Path] = []
    if not out.parent.is_dir():
        return removed
    for d in sorted(out.parent.glob(".*.staging-*")) + sorted(out.parent.glob(".*.old-*")):
        if not d.is_dir() or d.is_symlink():
            continue
        name, kind = _leftover_name(d)
        if name is None or not _owner_gone(d, min_age_s=min_age_s if name == out.name else None):
            continue
        final = out.parent / name
        if kind == "old" and not final.exists() and not final.is_symlink():
            with contextlib.suppress(OSError):
                os.replace(d, final)  # the previous results, orphaned mid-swap: put them back
                (final / OWNER).unlink()
        else:
            shutil.rmtree(d, ignore_errors=True)
        removed.append(d)
    return removed


def _leftover_name(directory: Path) -> tuple[str | None, str]:
    """``(NAME, "staging" | "old")`` of a ``.NAME.staging-XXXX`` / ``.NAME.old-XXXX`` folder, else ``(None, "")``."""
    for kind in ("staging", "old"):
        head, sep, _ = directory.name.rpartition(f".{kind}-")
        if sep and head.startswith(".") and len(head) > 1:
            return head[1:], kind
    return None, ""


def clean_stale_temp_files(final: str | os.PathLike) -> list[Path]:
    """Remove ``atomic_path`` temporary files of ``final`` (``.NAME.<pid>.*.tmp``) whose process is gone."""
    final = Path(final)
    removed: list[Path] = []
    if not final.parent.is_dir():
        return removed
    for f in final.parent.glob(f".{final.name}.*.tmp"):
        pid_text = f.name[len(final.name) + 2 :].split(".", 1)[0]
        if pid_text.isdigit() and f.is_file() and not f.is_symlink() and not _alive(int(pid_text)):
            with contextlib.suppress(OSError):
                f.unlink()
                removed.append(f)
    return removed


# ---------------------------------------------------------------------------------------------- interruption
class Interrupted(KeyboardInterrupt):
    """A run stopped by a signal (SIGINT or SIGTERM); ``signum`` says which (exit status ``128 + signum``)."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = int(signum)

    @property
    def signal_name(self) -> str:
        return signal.Signals(self.signum).name


class _Received:
    """What :func:`terminate_as_interrupt` saw: the first signal received (``signum``), if any."""

    def __init__(self) -> None:
        self.signum: int | None = None

    def check(self) -> None:
        """Raise :class:`Interrupted` when a signal arrived, even one whose exception some library code
        swallowed (an ``except BaseException`` that goes on, a callback whose error is ignored): call it before
        committing results."""
        if self.signum is not None:
            raise Interrupted(self.signum)


def _starting(signum, frame):  # noqa: ARG001 (a signal handler's signature)
    """SIGTERM while the command line starts (imports, options): nothing was written yet; one line, 128 + 15."""
    sys.stderr.write(f"interrupted ({signal.Signals(signum).name}): satchain was starting; nothing was written\n")
    sys.stderr.flush()
    os._exit(128 + int(signum))


def install_startup_handler() -> None:
    """Answer SIGTERM from the command line's first import on (a command that writes takes over with
    :func:`terminate_as_interrupt`; :func:`end_startup` puts the default back). Only for the process's own
    command line (``satchain`` or ``python -m satchain``), in the main thread, over the default action; the
    Python start-up before it (about 0.1 s) keeps the default: killed without a word, nothing written."""
    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    entry = os.path.basename(getattr(main, "__file__", "") or "") == "satchain" or (
        spec is not None and spec.name == "satchain.__main__"
    )
    if entry and threading.current_thread() is threading.main_thread():
        if signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None):
            signal.signal(signal.SIGTERM, _starting)


def end_startup() -> None:
    """The default SIGTERM action again, once a command may write (unless it installs its own handler)."""
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGTERM) is _starting:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[_Received]:
    """Within the block, SIGTERM raises :class:`Interrupted` (as Ctrl-C raises KeyboardInterrupt), so
    ``finally`` / ``except BaseException`` clean-ups run. Only in the main thread, and only where SIGTERM has
    its default action (a handler the caller installed is left alone); the previous handler is restored.

    Yields a record of the signals seen (SIGINT too, while Python's default SIGINT handler is in place); its
    ``check()`` re-raises one that was swallowed before it could stop the block."""
    received = _Received()
    if threading.current_thread() is not threading.main_thread():
        yield received
        return
    handlers = {}

    def _raise(signum, frame):
        if received.signum is None:
            received.signum = int(signum)
        raise Interrupted(signum)

    def _sigint(signum, frame):
        if received.signum is None:
            received.signum = int(signum)
        raise KeyboardInterrupt

    if signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None, _starting):  # the start-up's: taken over
        previous = signal.signal(signal.SIGTERM, _raise)
        handlers[signal.SIGTERM] = signal.SIG_DFL if previous is _starting else previous
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        handlers[signal.SIGINT] = signal.signal(signal.SIGINT, _sigint)
    previous_hook = sys.unraisablehook

    def _quiet(unraisable):  # an interruption raised where Python ignores exceptions (an import lock's
        if received.signum is not None and isinstance(unraisable.exc_value, KeyboardInterrupt):  # callback)
            return  # is recorded: check() raises it again, so no "Exception ignored" traceback for it
        previous_hook(unraisable)

    sys.unraisablehook = _quiet
    try:
        yield received
    finally:
        sys.unraisablehook = previous_hook
        for signum, previous in handlers.items():
            signal.signal(signum, previous)


# ---------------------------------------------------------------------------------------------- resources
def _parse_bytes(text: str) -> int:
    t = text.strip().upper().removesuffix("B").removesuffix("I")
    mult = {"K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
    try:
        if t and t[-1] in mult:
            return int(float(t[:-1]) * mult[t[-1]])
        return int(float(t))
    except ValueError:
        raise ConfigError(f"SATCHAIN_MEMORY_LIMIT = {text!r}: must be a number of bytes, e.g. 8G or 500M") from None


def _available_bytes() -> int:
    with contextlib.suppress(OSError, ValueError):
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    with contextlib.suppress(ValueError, OSError, AttributeError):
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    return 8 * 2**30


def memory_limit_bytes() -> int:
    """``SATCHAIN_MEMORY_LIMIT`` when set, else 80 % of the memory available now."""
    env = os.environ.get("SATCHAIN_MEMORY_LIMIT")
    if env:
        return _parse_bytes(env)
    return int(0.8 * _available_bytes())


def check_memory(need_bytes: float, what: str, *, fix: str = "") -> None:
    """Raise ResourceLimitError when ``what`` would need more than :func:`memory_limit_bytes`."""
    limit = memory_limit_bytes()
    if need_bytes > limit:
        hint = f"; {fix}" if fix else ""
        raise ResourceLimitError(
            f"{what}: needs about {need_bytes / 2**30:.2f} GiB of memory, {limit / 2**30:.2f} GiB allowed{hint} "
            "(the limit is 80% of the available memory, or SATCHAIN_MEMORY_LIMIT); nothing was written"
        )


def check_disk(need_bytes: float, paths: Iterable[str | os.PathLike], what: str, *, fix: str = "") -> None:
    """Raise ResourceLimitError when ``what`` would not fit on the disk holding the first of ``paths``."""
    for p in paths:
        d = Path(p).resolve().parent
        while not d.exists() and d != d.parent:
            d = d.parent
        try:
            free = shutil.disk_usage(d).free
        except OSError:
            return
        if need_bytes > free:
            hint = f"; {fix}" if fix else ""
            raise ResourceLimitError(
                f"{what}: needs about {need_bytes / 2**30:.2f} GiB on disk, {free / 2**30:.2f} GiB free in "
                f"{str(d)!r}{hint}; nothing was written"
            )
        return


def check_star_radius(radius_px: float | None, shape: tuple[int, int], *, annulus_px: float = 1.0) -> None:
    """``measure star --radius``: refuse a radius whose annuli would not fit, or that lies outside the image."""
    if radius_px is None:
        return
    from satchain.errors import InputError

    if not radius_px > 0 or radius_px != radius_px:
        raise InputError(f"--radius = {radius_px!r}: must be > 0 (pixels)")
    half_diag = 0.5 * (shape[0] ** 2 + shape[1] ** 2) ** 0.5
    if radius_px > half_diag:  # before the memory check: a huge radius is outside the image, not too big for RAM
        raise InputError(
            f"--radius = {radius_px:g}: outside the image ({shape[1]} x {shape[0]} px, half-diagonal "
            f"{half_diag:.0f} px); give a radius inside the image"
        )
    check_memory(48.0 * radius_px / annulus_px, f"--radius {radius_px:g}", fix="use a radius inside the image")


def check_dir_outputs(out_dir: str | os.PathLike | None, names: Iterable[str], inputs: Mapping[str, object]) -> None:
    """An output directory must not be an input, nor hold an input under a name the command writes.

    ``names`` are file names or ``fnmatch`` patterns (e.g. ``"*.png"``) written into ``out_dir``.
    """
    import fnmatch

    if out_dir is None:
        return
    out = Path(out_dir)
    for name, value in inputs.items():
        if value is None:
            continue
        p = Path(str(value))
        if _same(out, p) or (
            p.exists() and out.exists() and _same(out, p.parent) and any(fnmatch.fnmatch(p.name, pat) for pat in names)
        ):
            raise ConfigError(f"-o {str(out)!r}: would overwrite {name} {str(p)!r}; choose another output directory")


def check_inputs_outside(out_dir: str | os.PathLike, inputs: Mapping[str, object]) -> None:
    """``run -o DIR`` replaces DIR as a whole: refuse when an input file lies inside it."""
    out = Path(out_dir).resolve()
    for name, value in inputs.items():
        if value is None:
            continue
        p = Path(str(value)).resolve()
        if p == out or out in p.parents:
            raise ConfigError(
                f"-o {str(out_dir)!r}: the run would replace this directory, which holds {name} {str(value)!r}; "
                "copy that file elsewhere or choose another output directory"
            )


def check_output_files(outputs: Mapping[str, str | os.PathLike | None]) -> None:
    """An output file path must not be an existing directory (refused before any work)."""
    for name, value in outputs.items():
        if value is not None and Path(value).is_dir():
            raise ConfigError(f"{name} {str(value)!r}: is a directory; give a file path, e.g. {name} out.tif")


def check_input_file(path: str | os.PathLike, name: str, *, max_bytes: int = 64 * 2**20) -> Path:
    """A small text input (TOML, JSON) must be a regular file of at most ``max_bytes`` (not a device or a
    pipe that never ends)."""
    p = Path(path)
    if p.is_dir():
        raise SatchainIOError(f"{name} {str(p)!r}: is a directory; give a file")
    if not p.exists():
        raise SatchainIOError(f"{name} {str(p)!r}: not found")
    if not p.is_file():
        raise SatchainIOError(f"{name} {str(p)!r}: not a regular file (a device or a pipe?); give a file")
    size = p.stat().st_size
    if size > max_bytes:
        raise SatchainIOError(f"{name} {str(p)!r}: {size / 2**20:.0f} MiB is far too large for a {name}; wrong file?")
    return p


def not_utf8(path: str | os.PathLike, exc: UnicodeDecodeError, name: str) -> ConfigError:
    """The error for a text input that is not UTF-8 (a Latin-1 or Windows-1252 file): the file and the byte offset."""
    byte = exc.object[exc.start : exc.start + 1].hex() if isinstance(exc.object, bytes) else "?"
    return ConfigError(
        f"{name} {str(path)!r}: not UTF-8 text (byte 0x{byte} at offset {exc.start} cannot be decoded); TOML and "
        "JSON files must be UTF-8: save it as UTF-8 (e.g. iconv -f latin1 -t utf-8)"
    )


def nothing_measured(skipped, image, pixel_m: float | None, truth_path) -> Exception:
    """``measure auto`` measured no target: the error that says why (no finite pixel, every target skipped and
    the commonest reasons) and what to check, instead of an exit status 0 with empty tables."""
    import numpy as np

    from satchain.errors import InputError

    if image.size and not np.isfinite(image).any():
        return InputError("IMAGE: every pixel is NaN or inf; nothing was measured")
    targets = [s for s in skipped if not str(s.get("reason", "")).startswith("no measurement defined")]
    if not targets:
        return InputError(f"--truth {str(truth_path)!r}: lists no target to measure; nothing was measured")
    reasons: dict[str, int] = {}
    for s in targets:
        key = str(s.get("reason", "")).split(":", 1)[0]
        reasons[key] = reasons.get(key, 0) + 1
    common = "; ".join(f"{n} x {r}" for r, n in sorted(reasons.items(), key=lambda kv: -kv[1])[:3])
    scale = "unknown" if pixel_m is None else f"{pixel_m:g} m"
    return InputError(
        f"nothing was measured: all {len(targets)} targets of --truth {str(truth_path)!r} were skipped ({common}); "
        f"check that the truth file belongs to this image and the pixel size ({scale}; --pixel-m)"
    )


def _written_by_satchain(path: Path) -> bool:
    try:
        if path.suffix.lower() == ".png":
            from PIL import Image

            with Image.open(path) as img:
                return "satchain" in img.info
        if path.suffix.lower() == ".json":
            data = json.loads(path.read_text())
            return isinstance(data, dict) and str(data.get("format", "")).startswith("satchain")
    except Exception:  # unreadable: not ours
        return False
    return False


def check_sidecars(sidecars: Mapping[str, str | os.PathLike]) -> None:
    """Files a command writes beside ``-o`` (a ``.png`` preview, a ``.truth.json``) may replace only files
    satchain wrote itself; a user's file of that name is refused (``-o`` itself is the user's explicit choice)."""
    for name, value in sidecars.items():
        p = Path(value)
        if (p.exists() or p.is_symlink()) and not (p.is_file() and _written_by_satchain(p)):
            raise ConfigError(
                f"{name} {str(p)!r} exists and was not written by satchain; it would be overwritten: "
                "move it or choose another -o"
            )
