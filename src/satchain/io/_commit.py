"""Outputs committed together: the files that :func:`satchain.io.images.atomic_path` writes inside a
:func:`committed_together` block keep their temporary names until the block ends, then are all renamed in while
SIGINT and SIGTERM are held back (an image, its preview and its focal plane are replaced together or not at all)."""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

__all__ = ["CommitState", "committed_together", "defer_rename", "staged"]

#: per thread, the open :func:`committed_together` groups (innermost last): each a list of (temporary, final)
#: paths (a thread's writes never join another thread's group)
_LOCAL = threading.local()


def _groups() -> list[list[tuple[Path, Path]]]:
    if not hasattr(_LOCAL, "groups"):
        _LOCAL.groups = []
    return _LOCAL.groups


class CommitState:
    """What :func:`committed_together` did: ``committed`` becomes True once every file is under its final name."""

    committed: bool = False


@contextlib.contextmanager
def committed_together(check: Callable[[], None] | None = None) -> Iterator[CommitState]:
    """Commit the files that :func:`atomic_path` writes within the block together: each stays under its
    temporary name until the block ends; then ``check()`` (e.g. a signal that arrived) and, if it passes, all
    are renamed onto their final names with SIGINT and SIGTERM held back until the last rename (a signal
    received meanwhile is delivered after it: ``committed`` says the outputs were written). An error or an
    interruption before that removes every one of them, so no output of the group is replaced. A group inside
    another joins the outer one (committed at the outer's end). :func:`staged` names a file written but not
    yet committed."""
    state, groups = CommitState(), _groups()
    if groups:
        yield state
        return
    pending: list[tuple[Path, Path]] = []
    groups.append(pending)
    try:
        yield state
        if check is not None:
            check()
    except BaseException:
        for tmp, _ in pending:
            with contextlib.suppress(OSError):
                tmp.unlink()
        raise
    finally:
        groups.remove(pending)
    _rename_all(pending, state)


def _rename_all(pending: list[tuple[Path, Path]], state: CommitState) -> None:
    """Rename every file in with SIGINT and SIGTERM held back (their handlers replaced by one that records them:
    a signal reaches the main thread's handler whichever thread the system gave it to, so masking one thread
    would not do); a signal received meanwhile is raised after the last rename (``state.committed`` then
    True). Files not renamed in are removed."""
    import signal

    held: list[int] = []
    previous = {}
    if threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(signum) is not None:  # None: a handler not set from Python, left alone
                previous[signum] = signal.signal(signum, lambda n, _frame: held.append(n))
    done = 0
    try:
        try:
            for tmp, final in pending:
                os.replace(tmp, final)
                done += 1
            state.committed = True
        finally:
            for signum, handler in previous.items():
                signal.signal(signum, handler)
            if held:
                signal.raise_signal(held[0])  # to the handler now in place again
    except BaseException:
        for tmp, _ in pending[done:]:
            with contextlib.suppress(OSError):
                tmp.unlink()
        raise


def defer_rename(tmp: Path, final: Path) -> bool:
    """Hold ``tmp`` (the finished file for ``final``) for the open group's commit; False when no group is open."""
    groups = _groups()
    if not groups:
        return False
    groups[-1].append((Path(tmp), Path(final)))
    return True


def staged(path: str | os.PathLike) -> Path:
    """Where the file for ``path`` is now: its temporary name while a :func:`committed_together` group holds
    it, else ``path``."""
    final = Path(path)
    for group in _groups():
        for tmp, f in group:
            if f == final:
                return tmp
    return final
