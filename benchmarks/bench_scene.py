"""Scene render throughput (Mpx/s) for the paper layout at 3.5 cm, against naive per-pixel supersampling.

Run: ``python benchmarks/bench_scene.py [--rows 2048 --cols 2048 --ss 8]``

The reference renders the same window by point-sampling every pixel ``ss x ss`` times (matplotlib's
point-in-polygon for polygons, the analytic field for the star) and averaging: the simple method exact
coverage replaces. Its error (~1/ss at edges) is printed next to its speed.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from matplotlib.path import Path

from satchain.scene import paper_layout
from satchain.scene.targets import SiemensStar


def naive_render(scene, window, pixel_m, ss):
    """Point-sample every pixel ss x ss times, painter's order (the simple reference)."""
    row0, col0, h, w = window
    g = (np.arange(ss) + 0.5) / ss
    xs = ((col0 + np.arange(w))[:, None] + g[None, :]).ravel() * pixel_m
    ys = ((row0 + np.arange(h))[:, None] + g[None, :]).ravel() * pixel_m
    xx, yy = np.meshgrid(xs, ys)
    img = np.full(xx.shape, scene.background)
    pts = np.c_[xx.ravel(), yy.ravel()]
    x0, y0, x1, y1 = col0 * pixel_m, row0 * pixel_m, (col0 + w) * pixel_m, (row0 + h) * pixel_m
    for item in scene.items:
        bx0, by0, bx1, by1 = item.bbox_m()
        if bx1 < x0 or bx0 > x1 or by1 < y0 or by0 > y1:
            continue
        if isinstance(item, SiemensStar):
            dx, dy = xx - item.center_m[0], yy - item.center_m[1]
            r = np.hypot(dx, dy)
            val = item.mean + item.amplitude * np.sin(item.cycles * np.arctan2(dy, dx)) * (r >= item.inner_radius_m)
            img = np.where(r <= item.radius_m, val, img)
            continue
        for rings, refl in item.layers(pixel_m):
            for ring in rings:
                rx0, ry0 = ring.min(axis=0)
                rx1, ry1 = ring.max(axis=0)
                near = (pts[:, 0] >= rx0) & (pts[:, 0] <= rx1) & (pts[:, 1] >= ry0) & (pts[:, 1] <= ry1)
                if not near.any():
                    continue
                flat = img.reshape(-1)
                idx = np.flatnonzero(near)
                flat[idx[Path(ring).contains_points(pts[idx])]] = refl
    return img.reshape(h, ss, w, ss).mean(axis=(1, 3))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rows", type=int, default=2048)
    ap.add_argument("--cols", type=int, default=2048)
    ap.add_argument("--ss", type=int, default=8)
    ap.add_argument("--pixel-m", type=float, default=0.035)
    args = ap.parse_args()
    scene = paper_layout()
    p = args.pixel_m
    # a window over the Siemens star, vertical wedge, houses and the highway
    window = (0, round(70.0 / p), args.rows, args.cols)
    t0 = time.perf_counter()
    scene.render(window, pixel_m=p)
    t_exact = time.perf_counter() - t0
    ref_rows = min(args.rows, 128)
    ref_window = (window[0] + args.rows // 2, window[1], ref_rows, args.cols)
    t0 = time.perf_counter()
    naive = naive_render(scene, ref_window, p, args.ss)
    t_naive = time.perf_counter() - t0
    exact_part = scene.render(ref_window, pixel_m=p)
    mpx = args.rows * args.cols / 1e6
    mpx_ref = ref_rows * args.cols / 1e6
    print(f"paper layout at {p} m, window {window} ({mpx:.2f} Mpx)")
    print(f"exact coverage render : {t_exact:7.2f} s  {mpx / t_exact:7.2f} Mpx/s")
    print(
        f"naive {args.ss}x{args.ss} supersampling: {t_naive:7.2f} s  {mpx_ref / t_naive:7.4f} Mpx/s "
        f"(on {ref_rows} rows of it)"
    )
    print(f"speed ratio exact / naive: {(mpx / t_exact) / (mpx_ref / t_naive):.1f}x")
    err = np.abs(exact_part.astype(float) - naive)
    print(f"naive vs exact: max |diff| {err.max():.3g}, mean {err.mean():.3g} (~1/{args.ss} expected)")
    full = scene.shape_px(p)
    print(
        f"full scene {full[0]} x {full[1]} = {full[0] * full[1] / 1e6:.1f} Mpx; at this rate "
        f"~{full[0] * full[1] / 1e6 / (mpx / t_exact):.0f} s (single process)"
    )


if __name__ == "__main__":
    main()
