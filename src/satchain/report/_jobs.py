"""Figures drawn in a helper process while the run folder's other outputs are written (issue 21, point 3).

matplotlib draws in Python, so threads do not overlap it. A figure whose inputs are plain data (a comparison's
curves, a list of edge summaries) is therefore drawn by helper processes: ``python -m satchain.report._jobs``, given
the pickled calls on its standard input. A fresh interpreter, not a fork of this (possibly multi-threaded) one and
not :mod:`multiprocessing` (which would re-import a user's script that lacks an ``if __name__ == "__main__"``
guard). The caller goes on with what needs its live objects and calls :meth:`FigureJobs.wait` before anything
reads the figures. Every figure is written atomically by its own function; on an error or an interruption the
helpers are killed before the run removes its staging folder.

``SATCHAIN_FIGURE_PROCESSES``: how many helper processes (default: one less than the CPUs, at most 3; 0 draws
every figure in this process, as on a one-CPU machine).
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from satchain.errors import ConfigError, SatchainError

__all__ = ["FigureJobs", "figure_processes"]

_ENV = "SATCHAIN_FIGURE_PROCESSES"


def figure_processes() -> int:
    """Helper processes to draw figures with (``SATCHAIN_FIGURE_PROCESSES``, else CPUs - 1, at most 3)."""
    text = os.environ.get(_ENV)
    if text is not None and text.strip() != "":
        try:
            n = int(text)
        except ValueError:
            n = -1
        if n < 0:
            raise ConfigError(f"{_ENV} = {text!r}: must be a whole number >= 0 (0: draw in this process)")
        return n
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(0, min(3, cpus - 1))


class FigureJobs:
    """``submit(fn, *args, **kwargs)`` queues a call (``fn`` a module-level function, the arguments picklable);
    ``start()`` hands the queue to the helper processes (or runs it here, with none); ``wait()`` waits and raises
    a :class:`~satchain.errors.SatchainError` with a helper's error. As a context manager: ``start()`` on entry of
    the first :meth:`wait`, and on an error the helpers are killed."""

    def __init__(self, processes: int | None = None) -> None:
        self.processes = figure_processes() if processes is None else int(processes)
        self._queue: list[tuple[Callable[..., Any], tuple, dict]] = []
        self._procs: list[subprocess.Popen] = []

    def submit(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> None:
        if self.processes <= 0:
            fn(*args, **kwargs)
        else:
            self._queue.append((fn, args, kwargs))

    def start(self) -> None:
        """Start the helpers on the calls queued so far (round-robin)."""
        queue, self._queue = self._queue, []
        if not queue:
            return
        import satchain

        env = dict(os.environ)  # the helper imports this very satchain
        root = str(Path(satchain.__file__).resolve().parents[1])
        env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        env["MPLBACKEND"] = "Agg"
        n = min(self.processes, len(queue))
        for k in range(n):
            p = subprocess.Popen(
                [sys.executable, "-m", "satchain.report._jobs"],
                stdin=subprocess.PIPE,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                env=env,
            )
            self._procs.append(p)
            try:
                p.stdin.write(pickle.dumps(queue[k::n], protocol=pickle.HIGHEST_PROTOCOL))
                p.stdin.close()
            except BrokenPipeError:
                pass  # the helper died at start: wait() reports its error

    def wait(self) -> None:
        self.start()
        procs, self._procs = self._procs, []
        errors = []
        for p in procs:
            err = p.stderr.read().decode(errors="replace")
            p.stderr.close()
            if p.wait() != 0:
                errors.append(err.strip().splitlines()[-1] if err.strip() else f"exit status {p.returncode}")
        if errors:
            raise SatchainError(f"a figure could not be drawn (helper process): {errors[0]}")

    def kill(self) -> None:
        procs, self._procs = self._procs, []
        for p in procs:
            p.kill()
            p.wait()
            for f in (p.stdin, p.stderr):
                if f is not None and not f.closed:
                    f.close()

    def __enter__(self) -> FigureJobs:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.wait()
        else:
            self._queue.clear()
            self.kill()


def _main() -> int:
    """The helper: run the pickled calls from standard input; a failure's traceback on standard error."""
    import matplotlib

    matplotlib.use("Agg")
    for fn, args, kwargs in pickle.loads(sys.stdin.buffer.read()):
        fn(*args, **kwargs)
    return 0


if __name__ == "__main__":
    sys.exit(_main())
