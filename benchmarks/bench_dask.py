"""Dask against one process (issue 21, point 4): a tiled float32 GeoTIFF input, which the workers read window by
window themselves (the reader pickles as its path), simulated in one process and on a 2-worker LocalCluster
(1 thread each), both warm, interleaved ``--repeat`` times; prints both median times, their ratio and the
largest difference (0: the image is identical).

Usage: ``python benchmarks/bench_dask.py [--n 8192] [--repeat 3]`` (needs ``pip install 'satchain[dask]'``)
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from satchain import load_preset
from satchain.engine.distributed import simulate_distributed
from satchain.engine.simulate import Simulator
from satchain.engine.sources import SceneSource
from satchain.io.images import write_tiff
from satchain.scene import ImageScene


def main() -> None:
    from distributed import Client, LocalCluster

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=8192)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    n, repeat = a.n, a.repeat
    system = load_preset("ankarasat3")
    rng = np.random.default_rng(1)
    img = (0.2 + 0.6 * (rng.random((n // 64, n // 64)) > 0.5)).repeat(64, 0).repeat(64, 1).astype(np.float32)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "in.tif"
        write_tiff(path, img, pixel_m=0.035)
        del img
        src = SceneSource(ImageScene(path, pixel_m=0.035), pixel_m=0.035)

        def one():
            return Simulator(system, input_pixel_m=0.035, input_shape=src.shape_px).run(src)

        with (LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
              Client(cluster) as client):  # fmt: skip

            def dist():
                return simulate_distributed(src, system, scheduler=client)

            one(), dist()  # both warm: imports, FFT plans, the workers' first tasks
            times: dict = {one: [], dist: []}
            images = {}
            for _ in range(repeat):  # interleaved, so a change of load hits both
                for fn in times:
                    t = time.perf_counter()
                    image = fn()
                    times[fn].append(time.perf_counter() - t)
                    images[fn] = image
    t1, t2 = (float(np.median(times[f])) for f in (one, dist))
    diff = float(np.abs(images[one] - images[dist]).max())
    print(f"{n}^2 float32 GeoTIFF at 3.5 cm: one process {t1:.2f} s, 2-worker LocalCluster {t2:.2f} s "
          f"(ratio {t2 / t1:.2f}; goal <= 1.2), max |difference| {diff:.1e}")  # fmt: skip


if __name__ == "__main__":
    main()
