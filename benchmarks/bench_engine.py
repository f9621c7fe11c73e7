"""Engine throughput and memory against a simple full-frame NumPy reference, and a gigapixel run.

Run: ``python benchmarks/bench_engine.py [--size 4096] [--gigapixel [--giga-size 32768]]``
     ``python benchmarks/bench_engine.py --fft-ratio [--ratio-size 8192]``
     ``python benchmarks/bench_engine.py --stream [--stream-sizes 8192 16384] [--repeat 2]``  (24576: ~20 s a run)

(a) A synthetic 4096 x 4096 scene at 3.5 cm (edges and random rectangles, generated with NumPy from a
seed) through the AnkaraSat-3 system (k = 14): the engine (``Simulator.run``, default parameters) against
the simple reference -- ``numpy.fft.rfft2`` of the whole frame, times the system OTF (without the detector
aperture) at every frequency, ``irfft2``, then the 14 x 14 block mean (the detector footprint). Each runs in
its own subprocess, whose peak RSS (``VmHWM``) is read at its end; both hold the same float32 scene.
Accuracy: the reference is periodic, so the engine is also run with ``border="periodic"`` and compared on
every pixel; the default (mirror) run differs from it near the edges by the border rule, printed >= 40 px in.

(b) ``--gigapixel``: a 32768 x 32768 input rendered on the fly by a procedural source (analytic stripes,
a Siemens-like sector pattern and slanted edges, generated per window) -- never materialised.

(c) ``--fft-ratio``: ``satchain.simulate`` of the in-memory float32 synthetic scene (default 8192 x 8192) divided
by one float32 ``scipy.fft.rfft2`` + ``irfft2`` of the same array, both in this process, median of 3 each
(the bound: the engine should cost no more than one FFT pair of its input).

(d) ``--stream``: the streamed path of ``bench_stream.py`` (procedural input, coarse grid on disk, stage 2 in
tiles, image written to a tiled TIFF) at each of ``--stream-sizes``: throughput in input Mpx/s and peak RSS,
and the spread of the throughput (fastest / slowest; target: within 15 %), cold (each size in a fresh process)
and warm (after an untimed 4096^2 run in the same process).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from procedural import PIXEL_M, ProceduralScene

INTERIOR_PX = 40


def peak_rss_mib() -> float:
    """Peak resident set size of this process (VmHWM), MiB."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def synthetic_scene(n: int, seed: int = 0) -> np.ndarray:
    """Edges and random rectangles on a mid-grey background (float32, reflectance in [0.05, 0.95])."""
    rng = np.random.default_rng(seed)
    img = np.full((n, n), 0.3, dtype=np.float32)
    y, x = np.ogrid[:n, :n]
    img[(x + 0.1 * y) > n / 2] = 0.6  # a slanted ACT edge
    img[(y - 0.08 * x) > 0.7 * n] = 0.15  # a slanted ALT edge
    for _ in range(400):
        h, w = rng.integers(8, n // 8, size=2)
        r, c = rng.integers(0, n - h), rng.integers(0, n - w)
        img[r : r + h, c : c + w] = rng.uniform(0.05, 0.95)
    return img


def fft_ratio(n: int, *, repeats: int = 3) -> None:
    """(c): ``satchain.simulate`` / one float32 rfft2 + irfft2 of the same input, medians of ``repeats``."""
    import scipy.fft as sfft

    import satchain

    scene = synthetic_scene(n)
    system = satchain.load_preset("ankarasat3")
    from satchain.engine.simulate import SimParams

    workers = SimParams().workers

    def pair() -> None:
        sfft.irfft2(sfft.rfft2(scene, workers=workers), s=scene.shape, workers=workers)

    def engine() -> None:
        satchain.simulate(scene, system, pixel_m=PIXEL_M)

    times: dict[str, list[float]] = {"pair": [], "engine": []}
    pair()  # plans and pages, outside the timing
    for _ in range(repeats):  # interleaved, so a change of load hits both
        for name, fn in (("pair", pair), ("engine", engine)):
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    tp, te = (float(np.median(times[k])) for k in ("pair", "engine"))
    print(f"\n(c) {n} x {n} float32 scene, ankarasat3 at {PIXEL_M} m, {workers} FFT workers, median of {repeats}")
    print(f"  one float32 rfft2 + irfft2: {tp:.3f} s;  satchain.simulate: {te:.3f} s ({n * n / 1e6 / te:.1f} Mpx/s)")
    print(f"  engine / FFT pair: {te / tp:.2f}x   (target <= 1.0x)")
    print(f"  (fastest runs: pair {min(times['pair']):.3f} s, engine {min(times['engine']):.3f} s: ", end="")
    print(f"{min(times['engine']) / min(times['pair']):.2f}x)")


def stream_scaling(sizes: list[int], repeat: int = 1) -> None:
    """(d): streamed throughput (``bench_stream.py``'s streamed run, each size in its own process; the
    fastest of ``repeat`` rounds over the sizes, so that other load on the machine does not decide the spread),
    cold (a fresh process) and warm (the same process after an untimed 4096^2 streamed run: the process's
    one-time costs -- first touch of its working set, FFT plans -- paid, which a long-lived service or a batch
    pays once)."""
    import bench_stream

    runs = {}
    with tempfile.TemporaryDirectory() as d:
        for warm in (0, 4096):
            for _ in range(repeat):  # rounds over the sizes, so that a slow minute hits every size alike
                for n in sizes:
                    ns = argparse.Namespace(size=n, tile=512, margin=128, dir=d, tiff=None, stage1_mib=640, warmup=warm)
                    runs.setdefault((warm, n), []).append(bench_stream._run("streamed", ns))
                    os.remove(runs[warm, n][-1]["path"])
    rows = {}
    for key, rs in runs.items():
        rows[key] = dict(min(rs, key=lambda r: r["wall_s"]), peak_rss_mib=max(r["peak_rss_mib"] for r in rs))
    print(f"\n(d) streamed path (procedural input, coarse grid on disk, 512-px output tiles; best of {repeat})")
    print(f"  {'input':>13s} {'process':>7s} {'wall s':>8s} {'stage 1 s':>9s} {'Mpx/s':>7s} {'peak RSS MiB':>13s}")
    for (warm, n), r in rows.items():
        how, rss = "warm" if warm else "cold", r["peak_rss_mib"]
        print(f"  {n:>6d}^2 px {how:>7s} {r['wall_s']:8.1f} {r['stage1_s']:9.1f} {r['mpx_s']:7.1f} {rss:13.0f}")
    for warm in (0, 4096):
        mpx, how = [rows[warm, n]["mpx_s"] for n in sizes], "warm" if warm else "cold"
        print(f"  throughput fastest / slowest, {how}: {max(mpx) / min(mpx):.2f}   (target <= 1.15)")


# ------------------------------------------------------------------ children (one measurement each)
def _child_engine(n: int, out_path: str, border: str) -> dict:
    from satchain import load_preset
    from satchain.engine.simulate import SimParams, Simulator
    from satchain.engine.sources import ArraySource

    scene = synthetic_scene(n)
    t0 = time.perf_counter()
    system = load_preset("ankarasat3")
    sim = Simulator(system, input_pixel_m=PIXEL_M, input_shape=scene.shape, params=SimParams(border=border))
    img = sim.run(ArraySource(scene, pixel_m=PIXEL_M))
    wall = time.perf_counter() - t0
    np.save(out_path, img)
    return {"wall_s": wall, "tiles": len(sim.tiles), "D": sim.D, "shape": list(img.shape)}


def child_reference(n: int, out_path: str) -> dict:
    from satchain import load_preset, units
    from satchain.tf.budget import SystemOTF

    scene = synthetic_scene(n)
    t0 = time.perf_counter()
    system = load_preset("ankarasat3")
    k = int(round(system.gsd_alt_m / PIXEL_M))
    scale = float(
        units.ground_to_focal_cy_per_mm(1 / PIXEL_M, focal_length_m=system.focal_length_m, range_m=system.orbit.range_m)
    )
    fy = np.fft.fftfreq(n)[:, None] * scale
    fx = np.fft.rfftfreq(n)[None, :] * scale
    spec = np.fft.rfft2(scene)
    spec *= SystemOTF(system)(fx, fy, exclude=("detector",))
    filtered = np.fft.irfft2(spec, s=scene.shape)
    del spec
    m = n // k
    img = filtered[: m * k, : m * k].reshape(m, k, m, k).mean(axis=(1, 3))
    wall = time.perf_counter() - t0
    np.save(out_path, img)
    return {"wall_s": wall, "shape": list(img.shape)}


def child_gigapixel(n: int, out_path: str) -> dict:
    from satchain import load_preset
    from satchain.engine.simulate import Simulator

    src = ProceduralScene(n)
    t0 = time.perf_counter()
    sim = Simulator(load_preset("ankarasat3"), input_pixel_m=PIXEL_M, input_shape=src.shape_px)
    img = sim.run(src)
    wall = time.perf_counter() - t0
    np.save(out_path, img)
    return {"wall_s": wall, "tiles": len(sim.tiles), "D": sim.D, "shape": list(img.shape)}


def child_engine(n: int, out_path: str) -> dict:
    return _child_engine(n, out_path, "symmetric")


def child_engine_periodic(n: int, out_path: str) -> dict:
    return _child_engine(n, out_path, "periodic")


CHILDREN = {
    "engine": child_engine,
    "engine_periodic": child_engine_periodic,
    "reference": child_reference,
    "gigapixel": child_gigapixel,
}


def run_child(kind: str, n: int, out_path: str) -> dict:
    proc = subprocess.run(
        [sys.executable, os.path.abspath(__file__), "--child", kind, "--n", str(n), "--out", out_path],
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{kind} child failed:\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=4096, help="side of the in-memory input (px)")
    ap.add_argument("--gigapixel", action="store_true", help="also run the procedural 32768^2 input")
    ap.add_argument("--giga-size", type=int, default=32768)
    ap.add_argument("--fft-ratio", action="store_true", help="only (c): engine time / one float32 FFT pair")
    ap.add_argument("--ratio-size", type=int, default=8192)
    ap.add_argument("--stream", action="store_true", help="only (d): streamed throughput at --stream-sizes")
    ap.add_argument("--stream-sizes", type=int, nargs="+", default=[8192, 16384])
    ap.add_argument("--repeat", type=int, default=2, help="(d): runs per size, the fastest is printed")
    ap.add_argument("--child", choices=sorted(CHILDREN), help=argparse.SUPPRESS)
    ap.add_argument("--n", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--out", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        info = CHILDREN[a.child](a.n, a.out)
        info["peak_rss_mib"] = peak_rss_mib()
        print(json.dumps(info))
        return
    if a.fft_ratio or a.stream:
        if a.fft_ratio:
            fft_ratio(a.ratio_size)
        if a.stream:
            stream_scaling(a.stream_sizes, a.repeat)
        return

    n = a.size
    mpx = n * n / 1e6
    print(f"satchain engine benchmark: ankarasat3 at {PIXEL_M} m (k = 14), {os.cpu_count()} CPUs")
    with tempfile.TemporaryDirectory() as d:
        eng = run_child("engine", n, os.path.join(d, "engine.npy"))
        per = run_child("engine_periodic", n, os.path.join(d, "periodic.npy"))
        ref = run_child("reference", n, os.path.join(d, "reference.npy"))
        e, p, r = (np.load(os.path.join(d, f"{x}.npy")) for x in ("engine", "periodic", "reference"))
    m = INTERIOR_PX
    rows, cols = r.shape
    rel_all = float(np.max(np.abs(p[:rows, :cols] - r) / np.abs(r)))
    ei, ri = e[m : rows - m, m : cols - m], r[m : rows - m, m : cols - m]
    rel = float(np.max(np.abs(ei - ri) / np.abs(ri)))
    print(f"\n(a) {n} x {n} input ({mpx:.1f} Mpx) -> {e.shape[0]} x {e.shape[1]} output")
    print(f"  {'':28s} {'wall s':>8s} {'Mpx/s':>8s} {'peak RSS MiB':>13s}")
    for label, res in (("engine (Simulator.run)", eng), ("reference (full-frame FFT)", ref)):
        print(f"  {label:28s} {res['wall_s']:8.2f} {mpx / res['wall_s']:8.1f} {res['peak_rss_mib']:13.0f}")
    print(f"  speed ratio reference / engine: {ref['wall_s'] / eng['wall_s']:.2f}x   (target >= 3x)")
    print(f"  engine tiles: {eng['tiles']}, decimation D = {eng['D']}")
    label = "engine, border=periodic"
    print(f"  {label:28s} {per['wall_s']:8.2f} {mpx / per['wall_s']:8.1f} {per['peak_rss_mib']:13.0f}")
    print(f"  max relative difference engine(periodic) vs reference, all px: {rel_all:.2e}  (target <= 1e-4)")
    print(f"  max relative difference engine(mirror) vs reference, >= {m} px in: {rel:.2e}   (border rule)")
    ok = "ok" if eng["peak_rss_mib"] <= 1024 else "EXCEEDED"
    print(f"  peak RSS target for the engine: <= 1024 MiB -> {ok}")

    if a.gigapixel:
        g = a.giga_size
        gpx = g * g / 1e6
        with tempfile.TemporaryDirectory() as d:
            res = run_child("gigapixel", g, os.path.join(d, "giga.npy"))
            img = np.load(os.path.join(d, "giga.npy"))
        print(f"\n(b) {g} x {g} procedural input ({gpx / 1e3:.2f} Gpx, rendered per tile)", end="")
        print(f" -> {img.shape[0]} x {img.shape[1]}")
        print(f"  wall {res['wall_s']:.1f} s, {gpx / res['wall_s']:.1f} Mpx/s, {res['tiles']} tiles", end="")
        print(f", peak RSS {res['peak_rss_mib']:.0f} MiB")
        print(f"  peak RSS target: <= 2048 MiB -> {'ok' if res['peak_rss_mib'] <= 2048 else 'EXCEEDED'}")
        print(f"  output finite: {bool(np.all(np.isfinite(img)))}, range [{img.min():.3f}, {img.max():.3f}]")


if __name__ == "__main__":
    main()
