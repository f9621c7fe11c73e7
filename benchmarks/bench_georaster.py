"""Peak memory and throughput of `satchain simulate` on a large tiled uint16 GeoTIFF (issue 19: a 20000^2 input
in <= 2 GB peak RSS), with a reference in the same run: one plain windowed read of the same file with rasterio.

Writes the input (UTM, 0.098 m pixels, 512-px tiles, a nodata corner) in a child process, runs the CLI in
another (its own peak RSS from ``os.wait4``), checks the output (a COG in the input's CRS at the GSD) and prints:

    input 20000 x 20000 uint16 (0.80 GB); output 4000 x 4000 (streamed)
    simulate: 76.0 s, 5.3 Mpx/s of input, peak RSS 0.70 GB (limit 2 GB: ok)
    reference read of the file: 3.1 s (simulate / read = 24.5)

Usage: ``python benchmarks/bench_georaster.py [--n 20000] [--pixel-m 0.098] [--keep DIR]``
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import rasterio
from rasterio import Affine
from rasterio.windows import Window


def write_input(path: Path, n: int, px: float) -> None:
    prof = dict(driver="GTiff", width=n, height=n, count=1, dtype="uint16", crs="EPSG:32636",
                transform=Affine(px, 0, 500000.0, 0, -px, 4400000.0), tiled=True, blockxsize=512, blockysize=512,
                nodata=0, BIGTIFF="IF_SAFER")  # fmt: skip
    rng = np.random.default_rng(0)
    with rasterio.open(path, "w", **prof) as d:
        for r in range(0, n, 2048):
            h = min(2048, n - r)
            yy, xx = np.mgrid[r : r + h, 0:n]
            a = 26000 + 16000 * np.sign(np.sin(xx / 37.0) * np.cos(yy / 53.0)) + rng.normal(0, 300, (h, n))
            a = a.clip(1, 65535).astype(np.uint16)
            a[(yy < n // 40) & (xx < n // 30)] = 0  # a nodata corner
            d.write(a, 1, window=Window(0, r, n, h))


def read_whole_by_windows(path: Path) -> float:
    t = time.perf_counter()
    with rasterio.Env(GDAL_CACHEMAX=128), rasterio.open(path) as d:
        for r in range(0, d.height, 1024):
            d.read(1, window=Window(0, r, d.width, min(1024, d.height - r)))
    return time.perf_counter() - t


def run_child(cmd: list[str]) -> tuple[int, str, str, float]:
    """(exit status, stdout, stderr, peak RSS in GB) of one child process (``os.wait4``: that child only)."""
    with tempfile.TemporaryFile("w+") as fo, tempfile.TemporaryFile("w+") as fe:
        p = subprocess.Popen(cmd, stdout=fo, stderr=fe, text=True)
        _, status, usage = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        fo.seek(0), fe.seek(0)
        return p.returncode, fo.read(), fe.read(), usage.ru_maxrss * 1024 / 1e9


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=20000)
    ap.add_argument("--pixel-m", type=float, default=0.098)
    ap.add_argument("--keep", type=Path, default=None, help="work in this folder and keep the files")
    ap.add_argument("--write-only", type=Path, default=None, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.write_only is not None:
        return write_input(a.write_only, a.n, a.pixel_m)
    d = a.keep or Path(tempfile.mkdtemp(prefix="bench_georaster_"))
    d.mkdir(parents=True, exist_ok=True)
    src, out = d / f"in{a.n}.tif", d / f"out{a.n}.tif"
    if not src.exists():
        subprocess.run([sys.executable, __file__, "--n", str(a.n), "--pixel-m", str(a.pixel_m), "--write-only",
                        str(src)], check=True)  # fmt: skip
    out.unlink(missing_ok=True)
    t = time.perf_counter()
    cmd = [sys.executable, "-m", "satchain", "simulate", str(src), "--preset", "ankarasat3", "-o", str(out)]
    code, stdout, stderr, rss = run_child(cmd)
    wall = time.perf_counter() - t
    if code != 0:
        sys.exit(f"simulate failed: {stderr.strip()}")
    ref = read_whole_by_windows(src)
    with rasterio.open(out) as o:
        layout = o.tags(ns="IMAGE_STRUCTURE").get("LAYOUT")
        shape, gsd, crs = (o.height, o.width), o.transform.a, o.crs.to_string()
    streamed = "streamed" in stdout
    print(f"input {a.n} x {a.n} uint16 ({src.stat().st_size / 1e9:.2f} GB); output {shape[0]} x {shape[1]} "
          f"({'streamed' if streamed else 'in memory'}), {layout}, {crs}, {gsd:.4f} m")  # fmt: skip
    ok = "ok" if rss <= 2.0 else "OVER"
    print(f"simulate: {wall:.1f} s, {a.n * a.n / wall / 1e6:.1f} Mpx/s of input, peak RSS {rss:.2f} GB "
          f"(limit 2 GB: {ok})")  # fmt: skip
    print(f"reference read of the file: {ref:.1f} s (simulate / read = {wall / ref:.1f})")


if __name__ == "__main__":
    main()
