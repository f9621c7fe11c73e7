"""Figures drawn in a helper process while the run computes and writes its other outputs (issue 21, point 3).

matplotlib draws in Python, so threads do not overlap it. A figure whose inputs are plain data (a comparison's
curves, a list of edge summaries) is therefore drawn by helper processes: ``python -m satchain.report._jobs``, given
each pickled call on its standard input as it is submitted. A fresh interpreter, not a fork of this (possibly
multi-threaded) one and not :mod:`multiprocessing` (which would re-import a user's script that lacks an
``if __name__ == "__main__"`` guard). Calls may be submitted at any time before :meth:`FigureJobs.wait`: a run
hands the figures of its budget and scene to the helpers while it simulates, and those of its simulation while
it measures. The caller calls :meth:`FigureJobs.wait` before anything reads the figures. Every figure is written
atomically by its own function; on an error or an interruption the helpers are killed before the run removes its
staging folder.

``SATCHAIN_FIGURE_PROCESSES``: how many helper processes (default: one less than the CPUs, at most 3; 0 draws
every figure in this process, as on a one-CPU machine).
"""

from __future__ import annotations

import collections
import contextlib
import os
import pickle
import subprocess
import sys
import threading
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
    ``start()`` sets the helper processes to work on the queue, which may grow after that; ``wait()`` closes the
    queue, draws here what the helpers have not taken yet, waits for them and raises a
    :class:`~satchain.errors.SatchainError` with a helper's error. The queue is shared: each helper takes the
    next call from the front when it is free, this process takes from the back once its own work is done, so
    neither waits while calls are left. As a context manager: leaving it waits, or on an error kills the
    helpers."""

    def __init__(self, processes: int | None = None) -> None:
        self.processes = figure_processes() if processes is None else int(processes)
        self._calls: list[tuple[Callable[..., Any], tuple, dict]] = []
        self._todo: collections.deque[int] = collections.deque()
        self._cond = threading.Condition()
        self._closed = False  # no more calls: an idle helper may exit
        self._procs: list[subprocess.Popen] = []
        self._feeders: list[threading.Thread] = []
        self._results: dict[int, Any] = {}

    def submit(self, fn: Callable[..., Any], *args: Any, first: bool = False, **kwargs: Any) -> int:
        """Queue ``fn(*args, **kwargs)``; returns its number for :meth:`result` (its return value must pickle).
        ``first``: a long call, put at the front (a helper takes it early, so nobody waits for it at the end)."""
        with self._cond:
            i = len(self._calls)
            self._calls.append((fn, args, kwargs))
            if self.processes > 0:
                if first:
                    self._todo.appendleft(i)
                else:
                    self._todo.append(i)
                self._cond.notify()
        if self.processes <= 0:
            self._results[i] = _draw(fn, args, kwargs)
        return i

    def result(self, i: int) -> Any:
        """The return value of call ``i`` (after :meth:`wait`)."""
        return self._results.get(i)

    def _take(self, front: bool) -> int | None:
        """The next call: a helper (``front``) waits for one until the queue is closed; this process does not."""
        with self._cond:
            while front and not self._todo and not self._closed:
                self._cond.wait()
            if not self._todo:
                return None
            return self._todo.popleft() if front else self._todo.pop()

    def _hand_back(self, i: int) -> None:
        with self._cond:
            self._todo.append(i)  # not drawn by a helper: this process draws it
            self._cond.notify()

    def launch(self, preload: tuple[str, ...] = ()) -> None:
        """Start the helper processes now, importing ``preload`` (module names) while the caller computes what
        they will draw: their start-up (matplotlib, the report modules) is then off the critical path."""
        if self._procs or self.processes <= 0:
            return
        import satchain

        env = dict(os.environ)  # the helper imports this very satchain
        root = str(Path(satchain.__file__).resolve().parents[1])
        env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        env["MPLBACKEND"] = "Agg"
        for _ in range(self.processes):
            try:
                p = subprocess.Popen(
                    [sys.executable, "-m", "satchain.report._jobs", *preload],
                    stdin=subprocess.PIPE,
                    stdout=subprocess.PIPE,
                    stderr=subprocess.PIPE,
                    env=env,
                )
            except OSError:  # no helper can start here: every call is drawn in this process
                break
            self._procs.append(p)

    def start(self) -> None:
        """Set the helpers (launched here unless :meth:`launch` did, and only once a call is queued) to take
        calls from the queue, now and as they are submitted."""
        if self._feeders:
            return
        if not self._procs and self._todo:
            self.launch()
        for p in self._procs:
            t = threading.Thread(target=self._feed, args=(p,), daemon=True)
            self._feeders.append(t)
            t.start()

    def _feed(self, p: subprocess.Popen) -> None:
        """Hand the helper ``p`` one pickled call at a time from the front of the queue, until it is closed."""
        assert p.stdin is not None and p.stdout is not None  # launched with pipes
        try:
            while (i := self._take(front=True)) is not None:
                try:
                    call = pickle.dumps((i, *self._calls[i]), protocol=pickle.HIGHEST_PROTOCOL)
                except Exception:  # noqa: BLE001 - an argument that does not pickle: drawn here instead
                    self._hand_back(i)
                    continue
                p.stdin.write(b"%d\n" % len(call) + call)
                p.stdin.flush()
                head = p.stdout.readline().split()
                if len(head) != 2 or head[0] != b"ok":
                    self._hand_back(i)
                    raise BrokenPipeError
                self._results[i] = pickle.loads(p.stdout.read(int(head[1])))
            p.stdin.close()
        except (BrokenPipeError, OSError, ValueError):
            pass  # the helper died (its error is read in wait) or was killed

    def _close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()

    def wait(self) -> None:
        """Close the queue, draw here what the helpers have not taken, wait for them; a call a helper could not
        finish (it died, or the call raised there) is drawn here again, so only a call that fails here too
        raises."""
        self.start()
        self._close()
        if not self._feeders:  # launched, given nothing: let them exit
            for p in self._procs:
                assert p.stdin is not None  # launched with pipes
                with contextlib.suppress(OSError):
                    p.stdin.close()
        while True:
            while (i := self._take(front=False)) is not None:
                try:
                    self._results[i] = _draw(*self._calls[i])
                except SatchainError:
                    self.kill()
                    raise
            for t in self._feeders:
                t.join()
            if not self._todo:  # the feeders are done: nothing can be handed back any more
                break
        procs, self._procs, self._feeders = self._procs, [], []
        for p in procs:
            assert p.stderr is not None  # launched with pipes
            with contextlib.suppress(OSError):
                p.stderr.read()  # a helper's error: its call was drawn here instead (above)
            p.wait()
            _close(p)

    def kill(self) -> None:
        with self._cond:
            self._todo.clear()
            self._closed = True
            self._cond.notify_all()
        procs, self._procs = self._procs, []
        for p in procs:
            p.kill()
            p.wait()
        for t in self._feeders:
            t.join()
        self._feeders = []
        for p in procs:
            _close(p)

    def __enter__(self) -> FigureJobs:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.wait()
        else:
            self.kill()


def _draw(fn: Callable[..., Any], args: tuple, kwargs: dict) -> Any:
    """One call here; its failure reads as a helper's does."""
    try:
        return fn(*args, **kwargs)
    except Exception as exc:
        raise SatchainError(f"a figure could not be drawn: {type(exc).__name__}: {exc}") from exc


def _close(p: subprocess.Popen) -> None:
    for f in (p.stdin, p.stdout, p.stderr):
        if f is not None and not f.closed:
            with contextlib.suppress(OSError):
                f.close()


def _main() -> int:
    """The helper: for each call on standard input (a line ``N``, then the N bytes of the pickled
    ``(i, fn, args, kwargs)``), run it and answer ``ok M`` and the M bytes of its pickled return value; a
    failure's traceback goes to standard error (exit status 1). The end of the input ends it."""
    with contextlib.suppress(AttributeError, OSError):  # the run's own threads first: a helper's work can wait
        os.nice(10)
    import matplotlib

    matplotlib.use("Agg")
    import importlib

    for module in sys.argv[1:]:  # what the calls will need, imported while the caller computes
        importlib.import_module(module)
    stdin, out = sys.stdin.buffer, sys.stdout.buffer
    sys.stdout = sys.stderr  # what a figure prints cannot corrupt the answers
    while head := stdin.readline().strip():
        _, fn, args, kwargs = pickle.loads(stdin.read(int(head)))
        value = pickle.dumps(fn(*args, **kwargs), protocol=pickle.HIGHEST_PROTOCOL)
        out.write(b"ok %d\n" % len(value) + value)
        out.flush()
    return 0


def _exit_now(status: int) -> None:
    """End the helper without the interpreter's teardown (freeing matplotlib, numpy, scipy: tenths of a second
    that the run would wait for); every call's file was closed and renamed and every answer flushed before."""
    sys.stderr.flush()
    os._exit(status)


if __name__ == "__main__":
    _exit_now(_main())
