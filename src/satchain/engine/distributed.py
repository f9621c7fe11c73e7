"""The simulation engine on Dask: stage-1 tiles as independent tasks, on a cluster or local threads.

Stage 1 of :class:`~satchain.engine.simulate.Simulator` (read a tile of ground truth with its margins,
low-pass, decimate) is independent per tile: here every entry of ``Simulator.tiles`` becomes one Dask task
that calls :meth:`Simulator.decimate_tile`. The source travels to the workers (it must be picklable for
process-based workers: :class:`~satchain.engine.sources.ArraySource` and scene sources are), so scenes are
rendered on the fly where the tile is processed and never exist in full. The coarse tiles are assembled in
this process as they complete, then stage 2 (:meth:`Simulator.form_image`) and the sensor run here, exactly
as :meth:`Simulator.run` does -- the result is bit-for-bit the in-process result, noise included (the noise
generators belong to a fixed grid of output blocks, :mod:`satchain.engine.sensor`).

Optional extra: ``pip install 'satchain[dask]'`` (dask[array,distributed] and zarr), imported only when a
function here is called.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import threading
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from satchain._validate import check_choice
from satchain.config.system import ImagingSystem
from satchain.engine.sensor import OUTPUT_UNITS, SensorModel
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import as_ground_truth
from satchain.engine.tiling import Tile
from satchain.errors import ConfigError, SatchainIOError

__all__ = ["decimate_distributed", "simulate_distributed", "write_zarr"]

Progress = Callable[[int, int], None]
_EXTRA = "pip install 'satchain[dask]'"
#: seconds a connection to a scheduler address may take before it is refused as unreachable (distributed's default)
CONNECT_TIMEOUT_S = 30.0


def _require(module: str):
    """Import an optional dependency, or say which extra provides it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise ConfigError(
            f"the Dask engine needs the optional module {module!r}, which is not installed: {_EXTRA}"
        ) from None


def _decimate_tile(sim: Simulator, source, tile: Tile, keep_memory: bool = False) -> tuple[Tile, np.ndarray]:
    """One stage-1 task (module-level, so process workers can import it); ``keep_memory``: first
    :func:`satchain.engine._malloc.keep_freed_memory` in the worker process it runs in (Dask starts its workers with
    ``MALLOC_TRIM_THRESHOLD_=65536``, which also fixes glibc's mmap threshold at 128 KiB: every tile buffer was a
    fresh mapping faulted in again on each task, a stage-1 tile up to twice as slow as in one process)."""
    if keep_memory:
        from satchain.engine._malloc import keep_freed_memory

        keep_freed_memory()
    return tile, sim.decimate_tile(source, tile)


def _unreachable(address: str) -> SatchainIOError:
    return SatchainIOError(
        f"scheduler = {address!r}: cannot reach a Dask scheduler at that address in {CONNECT_TIMEOUT_S:g} s: check "
        "that the scheduler runs, its host and port, and the network between (or leave the scheduler out to run in "
        "this process)"
    )


def _probe_scheduler(address: str, timeout_s: float) -> None:
    """Refuse ``address`` unless a Dask scheduler answers there, all within ``timeout_s``: the connection, Dask's
    handshake and an ``identity`` request, on an event loop of their own (a notebook's loop is left alone).
    Something else listening there (an SSH banner read as a frame of 3 EiB, an HTTP server that waits for a
    request line) is named as not answering as a Dask scheduler, instead of failing or waiting in Client()."""
    import time

    deadline = time.monotonic() + timeout_s
    out: dict[str, Any] = {}
    t = threading.Thread(target=_identity, args=(address, deadline, out), name="satchain-probe", daemon=True)
    t.start()
    t.join(timeout_s + 2.0)
    reply, exc = out.get("reply"), out.get("error")
    if not out.get("connected"):
        raise _unreachable(address) from exc
    kind = reply.get("type") if isinstance(reply, dict) else None
    if kind == "Scheduler":
        return
    if kind is not None:
        answer = f"it answered as a Dask {kind}"
    elif t.is_alive() or isinstance(exc, TimeoutError):
        answer = f"no Dask handshake within {timeout_s:g} s"
    else:
        answer = f"what it sent is no Dask message: {type(exc).__name__ if exc is not None else repr(reply)[:40]}"
    raise SatchainIOError(
        f"scheduler = {address!r}: something listens there but does not answer as a Dask scheduler ({answer}): "
        "check the port (a Dask scheduler's is 8786 by default) and that the address is the scheduler's, not its "
        "dashboard's, a worker's or another service's"
    ) from exc


def _identity(address: str, deadline: float, out: dict[str, Any]) -> None:
    """The probe's thread: ``out["connected"]`` once a TCP connection is made (for tcp / tls / ws addresses;
    others once Dask connects), ``out["reply"]`` the answer to ``identity``, or ``out["error"]``."""
    import asyncio
    import socket
    import time

    from distributed.comm import connect, get_address_host_port

    async def identity():
        comm = await connect(address, timeout=max(deadline - time.monotonic(), 0.01))
        out["connected"] = True
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        try:
            host, port = get_address_host_port(address)
        except (ValueError, NotImplementedError):  # an address without host and port (inproc://, ucx://)
            pass
        else:
            socket.create_connection((host, port), timeout=max(deadline - time.monotonic(), 0.01)).close()
            out["connected"] = True
        out["reply"] = asyncio.run(asyncio.wait_for(identity(), max(deadline - time.monotonic(), 0.01)))
    except BaseException as exc:  # noqa: BLE001  (MemoryError: a banner read as a frame length)
        out["error"] = exc


def _client_for(scheduler) -> tuple[Any, bool]:
    """``(client, owned)``: None -> no client (local threads); an address -> a new client (closed by us);
    a ``distributed.Client`` -> itself."""
    if scheduler is None:
        return None, False
    if isinstance(scheduler, str):
        if "://" not in scheduler and ":" not in scheduler:
            raise ConfigError(
                f"scheduler = {scheduler!r}: must be None (local threads), a scheduler address such as "
                "'tcp://10.0.0.5:8786', or a distributed.Client"
            )
        distributed = _require("distributed")
        _probe_scheduler(scheduler, CONNECT_TIMEOUT_S)
        try:
            return distributed.Client(scheduler, timeout=CONNECT_TIMEOUT_S), True
        except (OSError, TimeoutError) as exc:  # refused, unknown host, or no answer (distributed's OSError)
            raise _unreachable(scheduler) from exc
    if hasattr(scheduler, "scatter") and hasattr(scheduler, "submit"):
        return scheduler, False
    raise ConfigError(
        f"scheduler = {type(scheduler).__name__}: must be None, a scheduler address string or a distributed.Client"
    )


def _decimate_threads(sim: Simulator, source, coarse: np.ndarray, progress: Progress | None) -> None:
    """Stage 1 on Dask's local threaded scheduler."""
    dask = _require("dask")
    from dask.callbacks import Callback

    task = dask.delayed(_decimate_tile, pure=False)
    parts = [task(sim, source, tile) for tile in sim.tiles]
    n_total, done = len(parts), [0]

    class _Count(Callback):
        def _posttask(self, key, result, dsk, state, worker_id):
            if isinstance(result, tuple) and len(result) == 2 and isinstance(result[0], Tile):
                done[0] += 1
                if progress is not None:
                    progress(done[0], n_total)

    with _Count():
        results = dask.compute(*parts, scheduler="threads", num_workers=max(1, os.cpu_count() or 1))
    for tile, block in results:
        coarse[tile.coarse.rows, tile.coarse.cols] = block


def _decimate_client(
    sim: Simulator, source, coarse: np.ndarray, client, progress: Progress | None, keep_memory: bool
) -> None:
    """Stage 1 on a distributed cluster: the simulator and the source are sent once to every worker,
    the tiles are gathered as they complete."""
    distributed = _require("distributed")
    sim_f, src_f = client.scatter([sim, source], broadcast=True, hash=False)
    run_id = uuid.uuid4().hex[:12]
    futures = [
        client.submit(
            _decimate_tile, sim_f, src_f, tile, keep_memory, key=f"satchain-decimate-{run_id}-{i}", pure=False
        )
        for i, tile in enumerate(sim.tiles)
    ]
    try:
        for n, (future, (tile, block)) in enumerate(distributed.as_completed(futures, with_results=True), 1):
            coarse[tile.coarse.rows, tile.coarse.cols] = block
            future.release()
            if progress is not None:
                progress(n, len(futures))
    finally:
        client.cancel(futures)
        del sim_f, src_f


def decimate_distributed(
    sim: Simulator,
    source,
    *,
    scheduler=None,
    progress: Progress | None = None,
    out: np.ndarray | None = None,
    keep_worker_memory: bool = True,
) -> np.ndarray:
    """Stage 1 of ``sim`` (:meth:`Simulator.decimate`) with its tiles spread over Dask: ``scheduler`` as for
    :func:`simulate_distributed`, or ``"local"`` for a ``distributed.LocalCluster`` on this machine (one
    worker process per core). Returns the coarse grid, identical to ``sim.decimate(source)``, written into
    ``out`` when given (e.g. a disk-backed array, :func:`satchain.engine.stream.coarse_store`).
    ``keep_worker_memory``: on a cluster, each worker process the tasks run in keeps freed memory for reuse
    (glibc: trim threshold 256 MiB, mmap threshold 32 MiB, set once by the first task), undoing Dask's
    ``MALLOC_TRIM_THRESHOLD_``, under which every tile buffer is faulted in afresh (tiles up to 2x slower);
    False leaves the workers' allocator as the cluster set it."""
    _require("dask")
    cluster = None
    if scheduler == "local":
        distributed = _require("distributed")
        cluster = distributed.LocalCluster(n_workers=max(1, os.cpu_count() or 1), threads_per_worker=1)
        scheduler = distributed.Client(cluster)
        owned = True
        client = scheduler
    else:
        client, owned = _client_for(scheduler)
    if out is not None and (out.shape != sim.n_coarse or out.dtype != np.float32):
        raise ConfigError(f"out: shape {out.shape}, dtype {out.dtype} must be {sim.n_coarse}, float32")
    coarse = np.empty(sim.n_coarse, dtype=np.float32) if out is None else out
    try:
        if client is None:
            _decimate_threads(sim, source, coarse, progress)
        else:
            _decimate_client(sim, source, coarse, client, progress, keep_worker_memory)
    finally:
        if owned:
            client.close()
        if cluster is not None:
            cluster.close()
    return coarse


def simulate_distributed(
    source,
    system: ImagingSystem,
    *,
    pixel_m: float | None = None,
    scheduler=None,
    params: SimParams = SimParams(),  # noqa: B008
    sensor: SensorModel | None = None,
    units: str = "reflectance",
    noise: bool = False,
    seed: int = 0,
    zarr_path: str | os.PathLike | None = None,
    zarr_chunk_px: int = 1024,
    progress: Progress | None = None,
    keep_worker_memory: bool = True,
) -> np.ndarray:
    """Simulate the satellite image of ``source`` with stage 1 spread over Dask workers.

    Parameters
    ----------
    source : array, scene or GroundTruth
        Ground truth (an array needs ``pixel_m``); sent to the workers, so it must be picklable for
        process-based workers.
    system : ImagingSystem
    pixel_m : float, optional
        Ground size of one input pixel (m), for an array ``source``.
    scheduler : None, str or distributed.Client
        None: Dask's threaded scheduler in this process; ``"tcp://HOST:PORT"``: connect to that scheduler
        (the connection is closed afterwards); a ``distributed.Client``: use it (e.g. on a LocalCluster).
    params, sensor, units, noise, seed
        As for :meth:`Simulator.run`; the result equals ``Simulator.run`` exactly.
    zarr_path : path, optional
        Also write the image there as a Zarr array (atomically: a temporary store renamed into place),
        chunks of ``zarr_chunk_px``, with the run's description in its attributes.
    progress : callable(done, total), optional
        Called as stage-1 tiles complete.
    keep_worker_memory : bool
        As for :func:`decimate_distributed`.

    Returns
    -------
    numpy.ndarray
        The image in ``units``, shape ``Simulator.output_shape`` (rows ALT, columns ACT).

    Examples
    --------
    >>> from satchain import load_preset
    >>> img = simulate_distributed(np.full((700, 700), 0.2), load_preset("ankarasat3"), pixel_m=0.035)
    >>> img.shape, bool(np.allclose(img, 0.2, atol=1e-6))
    ((50, 50), True)
    """
    check_choice("units", units, OUTPUT_UNITS)
    if sensor is None and (noise or units in ("dn", "electrons", "radiance")):
        raise ConfigError(f"units = {units!r}, noise = {noise!r}: need a SensorModel (radiometry) for that")
    if zarr_path is not None:
        _require("zarr")
    _require("dask")
    src = as_ground_truth(source, pixel_m=pixel_m)
    sim = Simulator(system, input_pixel_m=src.pixel_m, input_shape=src.shape_px, params=params, motion_seed=seed)
    sim.check_frame()  # before stage 1
    coarse = decimate_distributed(
        sim, src, scheduler=scheduler, progress=progress, keep_worker_memory=keep_worker_memory
    )
    img = sim.run(src, sensor=sensor, units=units, noise=noise, seed=seed, coarse=coarse)
    if zarr_path is not None:
        attrs = {
            "system": system.name,
            "input_pixel_m": src.pixel_m,
            "gsd_alt_m": system.gsd_alt_m,
            "gsd_act_m": system.gsd_act_m,
            "units": units,
            "noise": bool(noise),
            "seed": int(seed),
            "axes": ["y (ALT)", "x (ACT)"],
        }
        write_zarr(img, zarr_path, chunk_px=zarr_chunk_px, attrs=attrs)
    return img


def write_zarr(image: np.ndarray, path: str | os.PathLike, *, chunk_px: int = 1024, attrs: dict | None = None) -> Path:
    """Write a 2-D image as a Zarr array at ``path``, atomically: the store is written beside it under a
    temporary name and renamed into place (a previous store at ``path`` is replaced only once the new one is
    complete).

    Examples
    --------
    >>> import tempfile, zarr
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = write_zarr(np.arange(6.0).reshape(2, 3), Path(d) / "img.zarr", attrs={"units": "dn"})
    ...     z = zarr.open_array(str(p), mode="r")
    ...     z[:].tolist(), z.attrs["units"]
    ([[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]], 'dn')
    """
    zarr = _require("zarr")
    if not 1 <= int(chunk_px) <= 65536:
        raise ConfigError(f"zarr_chunk_px = {chunk_px!r}: must be in [1, 65536]")
    image = np.asarray(image)
    if image.ndim != 2:
        raise ConfigError(f"image: must be 2-D (rows, cols), got shape {image.shape}")
    target = Path(path)
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise SatchainIOError(f"zarr_path = {str(target)!r}: directory {str(parent)!r} does not exist")
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=parent))
    old = None
    try:
        chunks = (min(int(chunk_px), image.shape[0]), min(int(chunk_px), image.shape[1]))
        z = zarr.open_array(str(tmp / "store"), mode="w", shape=image.shape, chunks=chunks, dtype=image.dtype)
        z[...] = image
        z.attrs.update(dict(attrs or {}))
        if target.exists():
            old = parent / f".{target.name}.{uuid.uuid4().hex[:8]}.old"
            os.replace(target, old)
        os.replace(tmp / "store", target)
    except OSError as exc:
        if old is not None and not target.exists():
            os.replace(old, target)
        raise SatchainIOError(f"zarr_path = {str(target)!r}: cannot write ({exc})") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and target.exists():
            shutil.rmtree(old, ignore_errors=True)
    return target
