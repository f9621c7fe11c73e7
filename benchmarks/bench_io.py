"""Memory of simulating a large tiled TIFF: read window by window (satchain) vs read whole (the simple way).

A textured N x N uint8 tiled, zlib-compressed TIFF is written to a temporary folder; then, each in a fresh
process (so that the peak resident set size, ``ru_maxrss``, belongs to that case alone):

* windowed: ``ImageScene(path)`` (the file is read tile by tile as the engine asks) -> ``Simulator``;
* whole:    ``tifffile.imread(path) / 255`` -> ``ArraySource`` -> the same ``Simulator``.

Printed: the file's size, each case's peak RSS and time, the ratio whole / windowed, and the largest
difference between the two simulated images (they must agree: the windowed read is exact).

Run:  python benchmarks/bench_io.py [--quick] [--n 12000]   (default 12000: ~40 s)
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SRC = str(Path(__file__).resolve().parents[1] / "src")
PIXEL_M = 0.07

CHILD = """
import json, resource, sys, time
import numpy as np
sys.path.insert(0, {src!r})
from satchain import load_preset
from satchain.engine.simulate import Simulator
from satchain.engine.sources import ArraySource, SceneSource
mode, path, out = sys.argv[1:4]
t0 = time.perf_counter()
if mode == "windowed":
    from satchain.scene import ImageScene
    src = SceneSource(ImageScene(path))
else:
    import tifffile
    src = ArraySource(tifffile.imread(path) / 255.0, pixel_m={pixel_m})
sim = Simulator(load_preset("ankarasat3"), input_pixel_m={pixel_m}, input_shape=src.shape_px)
img = sim.form_image(sim.decimate(src))
np.save(out, img)
print(json.dumps({{"rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "time_s": time.perf_counter() - t0, "shape": list(img.shape)}}))
"""


def write_texture(path: Path, n: int) -> None:
    import tifffile

    y = np.arange(256)[:, None]
    x = np.arange(n)[None, :]

    def tiles():
        for r in range(0, n, 256):
            band = (128 + 60 * np.sin((x + r) / 37.0) * np.cos((y + r) / 23.0)).astype(np.uint8)
            for c in range(0, n, 256):
                t = band[:, c : c + 256]
                yield np.pad(t, ((0, 0), (0, 256 - t.shape[1]))) if t.shape[1] < 256 else t

    desc = json.dumps({"satchain": {"pixel_m": PIXEL_M}})
    tifffile.imwrite(path, tiles(), shape=(n, n), dtype=np.uint8, tile=(256, 256), compression="zlib", description=desc)


def run(mode: str, path: Path, out: Path) -> dict:
    code = CHILD.format(src=SRC, pixel_m=PIXEL_M)
    p = subprocess.run([sys.executable, "-c", code, mode, str(path), str(out)], capture_output=True, text=True)
    if p.returncode:
        raise SystemExit(p.stderr)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="a 4000 x 4000 image")
    ap.add_argument("--n", type=int, default=12000, help="image side, px")
    a = ap.parse_args()
    n = 4000 if a.quick else a.n
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        t0 = time.perf_counter()
        write_texture(d / "big.tif", n)
        print(
            f"image {n} x {n} uint8 tiled+zlib: {(d / 'big.tif').stat().st_size / 2**20:.1f} MiB on disk, "
            f"{n * n / 2**20:.0f} MiB as uint8, {n * n * 8 / 2**20:.0f} MiB as float64 "
            f"(written in {time.perf_counter() - t0:.1f} s)"
        )
        res = {m: run(m, d / "big.tif", d / f"{m}.npy") for m in ("windowed", "whole")}
        for m, r in res.items():
            print(f"{m:9s} peak RSS {r['rss_mib']:8.0f} MiB   time {r['time_s']:6.1f} s   output {r['shape']}")
        diff = float(np.max(np.abs(np.load(d / "windowed.npy") - np.load(d / "whole.npy"))))
        ratio = res["whole"]["rss_mib"] / res["windowed"]["rss_mib"]
        print(f"peak RSS whole / windowed = {ratio:.2f}; max |windowed - whole| = {diff:.2e} (reflectance)")


if __name__ == "__main__":
    main()
