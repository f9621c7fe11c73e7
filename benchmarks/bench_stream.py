"""Streamed simulation (coarse grid on disk, stage 2 by tiles, image written band by band) against the
full-frame path: wall time, throughput, peak RSS and the largest difference between the two.

Run: ``python benchmarks/bench_stream.py [--size 16384] [--tile 512] [--margin 128] [--stage1-mib 640] [--tiff PATH]``
     ``python benchmarks/bench_stream.py --margin-sweep``  (error vs margin, with and without the far field)
     ``python benchmarks/bench_stream.py --huge [--dir DIR]``  (100000 x 100000: a 9.3 GiB tiled uint8 TIFF
     of a repeated 4096-px procedural square is generated first, then streamed; ~13 GiB of disk)

The input (AnkaraSat-3 at 3.5 cm, k = 14) is the procedural ground truth of ``procedural.py``, which
``bench_engine.py`` uses too (stripes, sectors, slanted edges: generated per window, never held), or a tiled
TIFF (``--tiff``, read by window).
Each path runs in its own subprocess, whose peak RSS (``resource.getrusage``) is reported:

* streamed: ``Simulator.decimate`` into a disk-backed coarse grid, then
  ``satchain.engine.stream.write_streamed`` (reflectance, noise off) into a tiled TIFF;
* full frame: ``Simulator.run`` in memory (skipped when it does not fit; with ``--huge`` it runs on a
  ``--crop`` of the input instead, streamed (in 256-px tiles, so the windows are smaller than the crop's
  frame) and full frame both, so the difference is still measured).

The difference is printed as max |streamed - full| / (max - min of the full-frame image).
"""

from __future__ import annotations

import argparse
import contextlib
import io as stdio
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from procedural import PIXEL_M, ProceduralScene  # noqa: E402

GiB = 2**30


def _peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB on Linux


def _source(args):
    from satchain.engine.sources import SceneSource, as_ground_truth
    from satchain.scene import ImageScene

    if args.tiff:
        return SceneSource(ImageScene(args.tiff, pixel_m=PIXEL_M))
    return as_ground_truth(ProceduralScene(args.size))


class _Crop:
    """A window of another source as a source of its own."""

    def __init__(self, src, n: int):
        self.src, self.pixel_m = src, src.pixel_m
        r0, c0 = (src.shape_px[0] - n) // 2, (src.shape_px[1] - n) // 2
        self.r0, self.c0, self.shape_px = r0, c0, (n, n)

    def read(self, window):
        from satchain.engine.tiling import Window

        r, c, h, w = window
        return self.src.read(Window(r + self.r0, c + self.c0, h, w))


def worker(args) -> None:
    """One run in this process: prints a JSON line. ``args.warmup``: first a streamed run of that side, untimed
    (the process's one-time costs -- first touch of its working set, FFT plans -- are then paid)."""
    from satchain import load_preset
    from satchain.engine._malloc import keep_freed_memory
    from satchain.engine.simulate import SimParams, Simulator
    from satchain.engine.stream import choose_streamed, coarse_store, stream_bytes, write_streamed

    keep_freed_memory()  # the process set up as ``satchain simulate`` sets up its own
    if getattr(args, "warmup", 0):
        warm = argparse.Namespace(**{**vars(args), "size": args.warmup, "warmup": 0, "tiff": None, "crop": 0})
        with contextlib.redirect_stdout(stdio.StringIO()):
            worker(warm)
        os.remove(Path(args.dir) / f"{args.worker}-{args.warmup}.tif")
    src = _source(args)
    if args.crop:
        src = _Crop(src, args.crop)
    params = SimParams(
        stream_tile_px=args.tile, stream_margin_px=args.margin, max_tile_bytes=int(args.stage1_mib * 2**20)
    )
    sim = Simulator(load_preset("ankarasat3"), input_pixel_m=src.pixel_m, input_shape=src.shape_px, params=params)
    out = Path(args.dir) / f"{args.worker}-{src.shape_px[0]}.tif"
    t0 = time.perf_counter()
    info = {"auto_streamed": choose_streamed(sim), "stream_gib": stream_bytes(sim) / GiB}
    if args.worker == "streamed":
        with coarse_store(sim, args.dir) as coarse:
            sim.decimate(src, out=coarse)
            t1 = time.perf_counter()
            write_streamed(out, sim, coarse, pixel_m=sim.system.gsd_act_m, preview=False)
        info["stage1_s"] = t1 - t0
    else:
        from satchain.io import images as io

        sim.check_frame()
        io.write_tiff(out, sim.run(src).astype(np.float32))
    wall = time.perf_counter() - t0
    n_in = src.shape_px[0] * src.shape_px[1]
    info.update(
        path=str(out),
        wall_s=wall,
        mpx_s=n_in / 1e6 / wall,
        peak_rss_mib=_peak_rss_mib(),
        input=list(src.shape_px),
        output=list(sim.output_shape),
        coarse=list(sim.n_coarse),
        frame_gib=sim.frame_bytes / GiB,
        tile=args.tile,
        margin=args.margin,
    )
    print(json.dumps(info), flush=True)


def _run(kind: str, args, *, crop: int = 0) -> dict:
    tile = min(args.tile, 256) if crop else args.tile  # a crop's output is small: tiles well inside its frame
    cmd = [sys.executable, __file__, "--worker", kind, "--size", str(args.size), "--tile", str(tile)]
    cmd += ["--warmup", str(getattr(args, "warmup", 0))]
    cmd += ["--margin", str(args.margin), "--dir", args.dir, "--crop", str(crop), "--stage1-mib", str(args.stage1_mib)]
    if args.tiff:
        cmd += ["--tiff", args.tiff]
    p = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ})
    if p.returncode:
        raise SystemExit(f"{kind} run failed:\n{p.stderr[-3000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def _print(name: str, r: dict) -> None:
    extra = f", stage 1 {r['stage1_s']:.1f} s" if "stage1_s" in r else ""
    print(
        f"{name:26s} input {r['input'][0]} x {r['input'][1]} -> {r['output'][0]} x {r['output'][1]}: "
        f"{r['wall_s']:.1f} s{extra}, {r['mpx_s']:.1f} Mpx/s (input), peak RSS {r['peak_rss_mib']:.0f} MiB"
    )


def _difference(a_path: str, b_path: str) -> float:
    from satchain.io import images as io

    a, _ = io.read_image(a_path)
    b, _ = io.read_image(b_path)
    b = b.astype(np.float64)
    return float(np.max(np.abs(a.astype(np.float64) - b)) / np.ptp(b))


def make_huge_tiff(path: Path, n: int, *, period: int = 4096) -> None:
    """A ``n x n`` uint8 tiled TIFF: one ``period``-px square of the procedural ground truth, repeated (so it
    is written at disk speed rather than rendered pixel by pixel for hours)."""
    from satchain.engine.tiling import Window
    from satchain.io import images as io

    t = 256
    block = ProceduralScene(period).read(Window(0, 0, period, period))
    block = np.clip(np.round(block * 255), 0, 255).astype(np.uint8)
    block = np.tile(block, (2, 2))  # any tile-sized window of the repeated pattern is a slice of this

    def tiles():
        for r in range(0, n, t):
            for c in range(0, n, t):
                r0, c0 = r % period, c % period
                yield block[r0 : r0 + min(t, n - r), c0 : c0 + min(t, n - c)]

    io.write_tiff_tiles(path, tiles(), shape=(n, n), dtype=np.uint8, tile=(t, t), pixel_m=PIXEL_M)


def margin_sweep(n: int, tile: int) -> None:
    """Error of the streamed stage 2 against the full-frame one by margin, with and without the far field,
    on two ``n x n`` scenes: uniform noise with rectangles, and 8 x 8 black/white blocks (long straight
    edges: the worst case for a wrapped PSF tail)."""
    from satchain import load_preset
    from satchain.engine.simulate import SimParams, Simulator
    from satchain.engine.sources import ArraySource
    from satchain.engine.stream import stream_tiles

    rng = np.random.default_rng(0)
    noise = rng.uniform(0.1, 0.9, (n, n))
    for _ in range(20):
        h, w = rng.integers(5, n // 4, size=2)
        r, c = rng.integers(0, n - h), rng.integers(0, n - w)
        noise[r : r + h, c : c + w] = rng.uniform(0.1, 0.9)
    blocks = np.kron(rng.integers(0, 2, (8, 8)), np.ones((n // 8, n // 8)))
    system = load_preset("ankarasat3")
    for name, img in (("noise+rectangles", noise), ("8x8 blocks", blocks)):
        sim = Simulator(system, input_pixel_m=PIXEL_M, input_shape=img.shape)
        coarse = sim.decimate(ArraySource(img, pixel_m=PIXEL_M))
        full = sim.form_image(coarse)
        for m in (16, 32, 64, 128, 256):
            p = SimParams(stream_tile_px=tile, stream_margin_px=m)
            sm = Simulator(system, input_pixel_m=PIXEL_M, input_shape=img.shape, params=p)
            _, window = sm.tile_window((0, tile), (0, tile), m)
            if window[0] >= sm.frame_shape[0]:
                continue
            err = {}
            for far in (False, None):
                out, t0 = np.zeros(sm.output_shape), time.perf_counter()
                for r0, c0, t in stream_tiles(sm, coarse, far=far):
                    out[r0 : r0 + t.shape[0], c0 : c0 + t.shape[1]] = t
                err[far] = (np.max(np.abs(out - full)) / np.ptp(full), time.perf_counter() - t0)
            print(
                f"{name:17s} {n} px, {tile}-px tiles, margin {m:3d} px: max|diff|/range wrapped tail "
                f"{err[False][0]:.1e} ({err[False][1]:.1f} s), with far field {err[None][0]:.1e} ({err[None][1]:.1f} s)"
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=16384, help="procedural input side, px")
    ap.add_argument("--tiff", help="a tiled TIFF input instead (read by window, 3.5 cm pixels)")
    ap.add_argument("--tile", type=int, default=512, help="output tile side, px (SimParams.stream_tile_px)")
    ap.add_argument("--margin", type=int, default=128, help="output px margins (SimParams.stream_margin_px)")
    ap.add_argument("--stage1-mib", type=int, default=640, help="stage-1 tile memory (SimParams.max_tile_bytes)")
    ap.add_argument("--crop", type=int, default=0, help="full-frame comparison on a central crop of this side")
    ap.add_argument("--huge", action="store_true", help="100000 x 100000 from a generated tiled TIFF")
    ap.add_argument("--dir", help="scratch directory (default: a temporary one)")
    ap.add_argument("--margin-sweep", action="store_true", help="error vs margin on 4096-px scenes, 64-px tiles")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--warmup", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker(args)
        return
    if args.margin_sweep:
        margin_sweep(4096, 64)
        return
    with tempfile.TemporaryDirectory(dir=args.dir) as d:
        args.dir = d
        if args.huge:
            args.size, args.tile = 100_000, 2048
            args.tiff = str(Path(d) / "huge.tif")
            t0 = time.perf_counter()
            make_huge_tiff(Path(args.tiff), args.size)
            gib, dt = os.path.getsize(args.tiff) / GiB, time.perf_counter() - t0
            print(f"generated {args.tiff} ({gib:.1f} GiB) in {dt:.0f} s")
            args.crop = args.crop or 8192
        s = _run("streamed", args)
        _print("streamed", s)
        print(
            f"  (chosen automatically: {s['auto_streamed']}; full frame {s['frame_gib']:.2f} GiB of coarse frame, "
            f"streamed estimate {s['stream_gib']:.2f} GiB; tile {s['tile']} px, margin {s['margin']} px)"
        )
        if args.crop:
            s = _run("streamed", args, crop=args.crop)
            _print(f"streamed, {args.crop}-px crop", s)
        try:
            f = _run("full", args, crop=args.crop)
        except SystemExit as exc:
            print(f"full frame: did not run ({str(exc).splitlines()[-1]})")
            return
        _print("full frame" + (f", {args.crop}-px crop" if args.crop else ""), f)
        print(
            f"time streamed / full frame: {s['wall_s'] / f['wall_s']:.2f}; "
            f"peak RSS streamed / full frame: {s['peak_rss_mib'] / f['peak_rss_mib']:.2f}"
        )
        print(f"max |streamed - full frame| / range: {_difference(s['path'], f['path']):.2e}")


if __name__ == "__main__":
    main()
