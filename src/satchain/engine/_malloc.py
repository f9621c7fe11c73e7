"""The process's allocator, for the long tiled runs (glibc only; nothing elsewhere).

glibc serves a request above its mmap threshold (128 KiB at start, raised on the fly up to 32 MiB as large
blocks are freed) with a fresh mapping whose pages are faulted in on first touch, and gives freed heap memory
back above its trim threshold.  A tiled simulation allocates and frees the same few tile buffers again and again:
in a fresh process they are faulted in anew until glibc has adapted (a fresh ``satchain simulate`` of an
8192^2 scene spent ~0.15 s of its ~0.65 s stage 1 there), and in a Dask worker -- started with
``MALLOC_TRIM_THRESHOLD_=65536``, which also fixes the mmap threshold at 128 KiB -- on every task.
"""

from __future__ import annotations

__all__ = ["keep_freed_memory"]

_TUNED = False


def keep_freed_memory() -> None:
    """Once per process: let ``free`` keep up to 256 MiB and serve requests up to 32 MiB (glibc's largest
    mmap threshold) from the heap, so that tile buffers are reused instead of mapped and faulted in again.
    Called by processes satchain owns (``satchain simulate``, Dask workers), never by the library in a
    caller's process (nor by ``satchain run``: its default run is no faster so, with 0.1 GB more RSS)."""
    global _TUNED
    if _TUNED:
        return
    _TUNED = True
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name) if name else None
        if libc is not None and hasattr(libc, "mallopt"):
            libc.mallopt(-1, 256 << 20)  # M_TRIM_THRESHOLD
            libc.mallopt(-3, 32 << 20)  # M_MMAP_THRESHOLD (glibc's largest)
    except OSError:  # not glibc: nothing to tune
        pass
