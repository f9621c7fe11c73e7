"""``measure find`` benchmark: detection recall / precision, combined MTF at Nyquist error, throughput, memory.

Chart (rendered independently of satchain.measure, tests/measure/_render_chart.py): a grid of dark squares
(side 100 px) rotated by random angles of 3-12 deg (either sign) at random sub-pixel positions, on a bright
background; anisotropic Gaussian PSF (sigma 0.45 px ACT, 0.6 px ALT) x the square pixel, exact ESF per side;
Gaussian noise (contrast / noise = 175).  Truth: every side of every square, and the axis MTFs
``exp(-2 pi^2 s^2 f^2) |sinc f|``.

Printed:
* recall (truth sides found, centre within 3 px of the side line, angle within 0.5 deg) and precision
  (candidates matching a truth side);
* the error of the combined MTF at Nyquist per direction, for ``measure_found_edges`` and for the reference:
  ``measure_edge`` on hand-made ROIs built from the truth geometry, combined by a plain mean;
* throughput on a 4000 x 4000 image (1600 edges) (the chart tiled, fresh noise) for ``find_edges`` and for the whole
  ``measure_found_edges``, against a plain full-frame float64 Sobel gradient magnitude of the same image (the
  simplest possible edge detector, no segments, no ROIs) timed in the same run, and the peak traced memory.

Run:  PYTHONPATH=src python benchmarks/bench_find.py [--quick]
"""

from __future__ import annotations

import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
from scipy import ndimage as ndi

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render_chart import expected_edges, render_chart, true_mtf  # noqa: E402

from satchain.measure.edge import measure_edge  # noqa: E402
from satchain.measure.find import find_edges  # noqa: E402
from satchain.measure.find_mtf import measure_found_edges  # noqa: E402

SX, SY, NOISE = 0.45, 0.6, 0.004


def make_chart(n_side: int, rng: np.random.Generator):
    """(image, squares) with n_side x n_side squares on a 200 px grid."""
    squares = []
    for i in range(n_side):
        for j in range(n_side):
            rot = rng.uniform(3.0, 12.0) * rng.choice([-1, 1])
            squares.append((100 + 200 * j + rng.uniform(0, 1), 100 + 200 * i + rng.uniform(0, 1), 100, rot))
    img = render_chart((200 * n_side, 200 * n_side), squares, sx=SX, sy=SY, noise=NOISE, rng=rng)
    return img, squares


def match(candidates, truth):
    """(number of truth sides found, number of candidates that match a truth side)."""
    used = set()
    n_found = 0
    for px, py, ang, direction in truth:
        t = np.deg2rad(ang)
        ux, uy = np.sin(t), np.cos(t)
        for k, c in enumerate(candidates):
            near = abs((c.center_xy[0] - px) * uy - (c.center_xy[1] - py) * ux) < 3
            close = np.hypot(c.center_xy[0] - px, c.center_xy[1] - py) < 20
            if near and close and abs(c.angle_deg - ang) < 0.5 and c.direction == direction and k not in used:
                used.add(k)
                n_found += 1
                break
    return n_found, len(used)


def truth_roi(px, py, ang, direction, side=100, half_w=16, trim=25):
    """Hand-made ROI from the truth geometry: the central part of the side, +-half_w across it."""
    t = np.deg2rad(ang)
    half = side / 2 - trim
    if direction == "ACT":
        slope = np.tan(t)  # dx/dy
        xs = (px - half * slope, px + half * slope)
        return (int(min(xs) - half_w), int(py - half), int(max(xs) + half_w) + 1, int(py + half) + 1)
    slope = 1.0 / np.tan(t)  # dy/dx
    ys = (py - half * slope, py + half * slope)
    return (int(px - half), int(min(ys) - half_w), int(px + half) + 1, int(max(ys) + half_w) + 1)


def accuracy(n_side: int, rng) -> None:
    img, squares = make_chart(n_side, rng)
    truth = expected_edges(squares)
    t0 = time.perf_counter()
    res = measure_found_edges(img)
    dt = time.perf_counter() - t0
    s = find_edges(img)
    n_found, n_match = match(s.candidates, truth)
    print(f"chart {img.shape[1]} x {img.shape[0]} px, {len(squares)} squares, {len(truth)} sides")
    print(
        f"  detection: recall {n_found}/{len(truth)} = {n_found / len(truth):.3f}, "
        f"precision {n_match}/{len(s)} = {n_match / max(len(s), 1):.3f}, rejected {s.rejection_counts()}"
    )
    ref = {"ACT": [], "ALT": []}
    for px, py, ang, direction in truth:
        ref[direction].append(measure_edge(img, roi=truth_roi(px, py, ang, direction)).mtf_at_nyquist)
    print(f"  MTF at Nyquist (measure_found_edges {dt:.2f} s):")
    for d, sig in (("ACT", SX), ("ALT", SY)):
        tr = float(true_mtf(0.5, sig))
        c = res.combined[d]
        r_mean = float(np.mean(ref[d]))
        print(
            f"    {d}: truth {tr:.4f}; found {c.mtf_at_nyquist:.4f} +- {c.mtf_at_nyquist_sigma:.4f} "
            f"({c.n_edges} edges, error {c.mtf_at_nyquist - tr:+.4f} = "
            f"{(c.mtf_at_nyquist - tr) / c.mtf_at_nyquist_sigma:+.1f} sigma); "
            f"reference on truth ROIs {r_mean:.4f} ({len(ref[d])} edges, error {r_mean - tr:+.4f})"
        )
    return img


def throughput(tile: np.ndarray, size: int, rng) -> None:
    reps = int(np.ceil(size / tile.shape[0]))
    big = np.tile(tile, (reps, reps))[:size, :size]
    big = big + rng.normal(0.0, NOISE, big.shape)  # fresh noise on top (the tile's is repeated)
    big = big.astype(np.float32)
    mpx = big.size / 1e6
    t0, c0 = time.perf_counter(), time.process_time()
    gx = ndi.sobel(big.astype(np.float64), axis=1)
    gy = ndi.sobel(big.astype(np.float64), axis=0)
    mag = np.hypot(gx, gy)
    t_ref, c_ref = time.perf_counter() - t0, time.process_time() - c0
    del gx, gy, mag
    tracemalloc.start()
    t0, c0 = time.perf_counter(), time.process_time()
    s = find_edges(big)
    t_find, c_find = time.perf_counter() - t0, time.process_time() - c0
    _, peak_find = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    s200 = find_edges(big, max_edges=200)
    t0 = time.perf_counter()
    res = measure_found_edges(big, search=s200)
    t_meas = time.perf_counter() - t0
    print(f"throughput on {size} x {size} float32 ({mpx:.0f} Mpx, {big.nbytes / 2**20:.0f} MiB):")
    print(f"  reference full-frame float64 Sobel magnitude: {t_ref:.2f} s wall, {c_ref:.2f} s CPU")
    print(
        f"  find_edges: {t_find:.2f} s wall, {c_find:.2f} s CPU ({mpx / t_find:.1f} Mpx/s wall; "
        f"CPU {c_find / c_ref:.2f} x the Sobel reference), {len(s)} edges,"
        f" peak traced memory {peak_find / 2**20:.0f} MiB = {peak_find / big.nbytes:.2f} x the image"
    )
    print(
        f"  measuring the 200 longest edges (max_edges=200, the CLI default) + combining: {t_meas:.2f} s "
        f"({t_meas / len(res.edges) * 1e3:.0f} ms per edge); total {mpx / (t_find + t_meas):.1f} Mpx/s"
    )


def main() -> None:
    quick = "--quick" in sys.argv
    rng = np.random.default_rng(12345)
    img = accuracy(3 if quick else 5, rng)
    throughput(img, 2000 if quick else 4000, rng)


if __name__ == "__main__":
    main()
