"""The Dask engine equals the in-process engine exactly, on a distributed LocalCluster and on threads."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

pytest.importorskip("dask")
distributed = pytest.importorskip("distributed")
zarr = pytest.importorskip("zarr")

from _reference import make_scene  # noqa: E402

from satchain import load_preset  # noqa: E402
from satchain.engine.distributed import simulate_distributed, write_zarr  # noqa: E402
from satchain.engine.sensor import SensorModel  # noqa: E402
from satchain.engine.simulate import SimParams, Simulator  # noqa: E402
from satchain.engine.sources import ArraySource  # noqa: E402
from satchain.engine.tiling import Window  # noqa: E402
from satchain.errors import ConfigError  # noqa: E402

BASE = load_preset("ankarasat3")
SENSOR = SensorModel(electrons_per_unit=20000.0, offset_e=100.0, dark_e=50.0, read_noise_e=10.0, full_well_e=60000.0)
PARAMS = SimParams(max_tile_bytes=12 * 2**20, workers=1)  # many small tiles


class Stripes:
    """A procedural ground truth: ALT/ACT sine stripes and a diagonal edge, rendered per window."""

    pixel_m = 0.04
    shape_px = (735, 784)

    def read(self, window: Window) -> np.ndarray:
        y = np.arange(window.row0, window.row0 + window.height)[:, None]
        x = np.arange(window.col0, window.col0 + window.width)[None, :]
        return 0.5 + 0.2 * np.sin(2 * np.pi * x / 97.0) * np.cos(2 * np.pi * y / 61.0) + 0.1 * (x + 0.6 * y > 700)


@pytest.fixture(scope="module")
def client():
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster,
        distributed.Client(cluster) as c,
    ):
        yield c


def test_local_cluster_equals_in_process_with_noise(client, tmp_path):
    img = make_scene((1120, 980), np.random.default_rng(4))
    sim = Simulator(BASE, input_pixel_m=0.035, input_shape=img.shape, params=PARAMS)
    assert len(sim.tiles) > 10
    kw = dict(sensor=SENSOR, units="dn", noise=True, seed=11)
    expected = sim.run(ArraySource(img, pixel_m=0.035), **kw)
    calls = []
    out = simulate_distributed(
        img,
        BASE,
        pixel_m=0.035,
        scheduler=client,
        params=PARAMS,
        zarr_path=tmp_path / "img.zarr",
        zarr_chunk_px=32,
        progress=lambda d, t: calls.append((d, t)),
        **kw,
    )
    np.testing.assert_array_equal(out, expected)
    assert calls[-1] == (len(sim.tiles), len(sim.tiles)) and len(calls) == len(sim.tiles)
    z = zarr.open_array(str(tmp_path / "img.zarr"), mode="r")
    np.testing.assert_array_equal(z[:], expected)
    assert z.chunks == (32, 32) and z.attrs["units"] == "dn" and z.attrs["seed"] == 11


def test_procedural_source_on_cluster_and_threads(client):
    """A source rendered on the fly in the workers; also the local threaded scheduler (no client)."""
    src = Stripes()
    sim = Simulator(BASE, input_pixel_m=src.pixel_m, input_shape=src.shape_px, params=PARAMS)
    expected = sim.run(src)
    np.testing.assert_array_equal(simulate_distributed(src, BASE, scheduler=client, params=PARAMS), expected)
    np.testing.assert_array_equal(simulate_distributed(src, BASE, params=PARAMS), expected)


def test_zarr_write_is_atomic_replacement(tmp_path):
    p = tmp_path / "out.zarr"
    write_zarr(np.zeros((4, 5)), p)
    write_zarr(np.ones((3, 3)), p, attrs={"units": "dn"})
    z = zarr.open_array(str(p), mode="r")
    assert z.shape == (3, 3) and np.all(z[:] == 1) and z.attrs["units"] == "dn"
    assert sorted(q.name for q in tmp_path.iterdir()) == ["out.zarr"]  # no temporary stores left


def test_errors_name_the_parameter(tmp_path):
    img = np.full((700, 700), 0.2)
    with pytest.raises(ConfigError, match="scheduler = 'fast'"):
        simulate_distributed(img, BASE, pixel_m=0.035, scheduler="fast")
    with pytest.raises(ConfigError, match="units = 'dn'"):
        simulate_distributed(img, BASE, pixel_m=0.035, units="dn")
    with pytest.raises(ConfigError, match="zarr_chunk_px = 0"):
        write_zarr(img, tmp_path / "x.zarr", chunk_px=0)


def test_simulator_and_sources_survive_pickling_for_process_workers():
    """Process-based workers receive the simulator and the source by (cloud)pickle."""
    cloudpickle = pytest.importorskip("cloudpickle")
    img = make_scene((700, 630), np.random.default_rng(9), rectangles=3)
    src = ArraySource(img, pixel_m=0.035)
    sim = Simulator(BASE, input_pixel_m=0.035, input_shape=img.shape, params=PARAMS)
    sim2, src2 = cloudpickle.loads(cloudpickle.dumps((sim, src)))
    tile = sim.tiles[len(sim.tiles) // 2]
    np.testing.assert_array_equal(sim2.decimate_tile(src2, tile), sim.decimate_tile(src, tile))
    stripes = cloudpickle.loads(cloudpickle.dumps(Stripes()))
    np.testing.assert_array_equal(stripes.read(Window(3, 4, 5, 6)), Stripes().read(Window(3, 4, 5, 6)))


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's allocator")
def test_workers_keep_freed_tile_buffers_despite_dasks_trim_setting():
    """Dask starts workers with MALLOC_TRIM_THRESHOLD_=65536, which fixes glibc's mmap threshold at 128 KiB, so
    every tile buffer would be a fresh mapping faulted in again on each task. Once a stage-1 task has run, a
    freed 16 MiB buffer stays in the heap (glibc's own statistics) and is reused."""
    code = textwrap.dedent(
        """
        import ctypes, ctypes.util
        import numpy as np
        libc = ctypes.CDLL(ctypes.util.find_library("c"))
        class Info(ctypes.Structure):
            _fields_ = [(k, ctypes.c_size_t) for k in
                        "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]
        libc.mallinfo2.restype = Info
        def kept_after_free():
            a = np.ones(2**21)  # 16 MiB
            del a
            return libc.mallinfo2().fordblks >= 2**24
        before = kept_after_free()
        from satchain.engine._malloc import keep_freed_memory
        keep_freed_memory()
        print(before, kept_after_free())
        """
    )
    env = {**os.environ, "MALLOC_TRIM_THRESHOLD_": "65536"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=False)
    if "mallinfo2" in out.stderr:
        pytest.skip("glibc without mallinfo2")
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "True"]
