"""False-alarm and detection rates of the clipping test (:func:`satchain.measure.find_clipping`, issue 18).

A sweep of edges, gratings and Siemens stars rendered here (Gaussian blur, pixel integration by 8 x 8
Gauss-Legendre nodes so that exact plateaus are exact, as in tests/measure/test_clipping.py), at random
angles, sub-pixel phases, blurs, levels and noise, each once as rendered and once cut flat by ``np.minimum``
at a level inside its swing (or at the integer type's maximum).  Prints, per target family, the share of
unclipped regions named clipping (false alarms: should be 0) and of clipped ones named (detection), and the
same for ``measure_edge`` (refused or flagged as clipped).  Pixel-sharp edges (blur below 0.2 px, critical
tilts included) are the hard case for false alarms; their clipped detection is not expected (a cut is the
same as a sharp edge's corner, see :mod:`satchain.measure._clipping`).

Run:  PYTHONPATH=src python benchmarks/bench_clipping.py [--n 200] [--seed 0]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from satchain.errors import InputError
from satchain.measure import find_clipping
from satchain.measure.edge import measure_edge

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render_clip import render_edge, render_grating, render_star  # noqa: E402  (the tests' exact renders)


def edge(shape, angle_deg, blur, phase, lo, hi):
    return render_edge(angle_deg, blur, phase, lo=lo, hi=hi, shape=shape)


def grating(period, blur, phase, lo, hi, shape=(20, 96)):
    return render_grating(period, blur, phase, lo=lo, hi=hi, shape=shape)


def star(center, blur, n=32):
    return render_star(n, center, blur)


def edge_named(img) -> bool:
    try:
        r = measure_edge(img)
    except InputError as exc:
        return "clipped" in str(exc) or "saturat" in str(exc)
    return "clipping" in r.flags


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=120, help="cases per family")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    counts: dict[str, list[int]] = {}

    def tally(name, named_clean, named_cut):
        c = counts.setdefault(name, [0, 0, 0])
        c[0] += 1
        c[1] += bool(named_clean)
        c[2] += bool(named_cut)

    for _ in range(args.n):
        noise = float(rng.choice([0.0, 0.0, 1e-3, 0.01]))
        lo, hi = sorted(rng.uniform(0.02, 0.95, 2))
        if hi - lo < 0.2:
            hi = min(lo + 0.3, 1.0)
        img = edge((80, 80), rng.uniform(3.0, 42.0), rng.uniform(0.3, 4.0), rng.uniform(-0.5, 0.5, 2), lo, hi)
        img = img + rng.normal(0, noise * (hi - lo), img.shape)
        cut = np.minimum(img, lo + rng.uniform(0.6, 0.9) * (hi - lo))
        fam = "edge, noise-free" if noise == 0 else "edge, noisy"
        tally(fam, find_clipping(img), find_clipping(cut))
        tally(f"measure_edge ({fam})", edge_named(img), edge_named(cut))

        period, blur = float(rng.choice([6.0, 8.0, 12.0, 16.0, 24.0])), rng.uniform(0.6, 1.2)
        g = grating(period, blur, rng.uniform(0, period), 0.1, 0.7)
        g = g + rng.normal(0, noise * 0.6, g.shape)
        level = 0.1 + 0.5 * float(g.max() - 0.1)
        tally(
            f"grating {'>= 12' if period >= 12 else '6-8'} px, {'noise-free' if noise == 0 else 'noisy'}",
            find_clipping(g),
            find_clipping(np.minimum(g, level)),
        )

        s = star(40.0 + rng.uniform(-0.5, 0.5, 2), rng.uniform(0.5, 1.0)) + rng.normal(0, noise * 80, (81, 81))
        tally(f"star, {'noise-free' if noise == 0 else 'noisy'}", find_clipping(s), find_clipping(np.minimum(s, 125.0)))

        crit = float(rng.choice([0.0, 14.036, 18.435, 26.565, 45.0, rng.uniform(2.0, 44.0)]))
        sharp = edge((60, 60), crit, rng.uniform(1e-3, 0.2), rng.uniform(-0.5, 0.5, 2), lo, hi)
        tally(
            "edge, pixel-sharp (blur < 0.2 px), any tilt",
            find_clipping(sharp),
            find_clipping(np.minimum(sharp, 0.5 * (lo + hi))),
        )

        u = 1000 + 30000 * edge(
            (80, 80), rng.uniform(3.0, 42.0), rng.uniform(0.4, 2.0), rng.uniform(-0.5, 0.5, 2), 0, 1
        )
        u = np.round(u + rng.normal(0, rng.choice([0.0, 0.4, 5.0, 40.0]), u.shape))
        tally(
            "uint16 (cut at 65535)",
            find_clipping(u.astype(np.uint16)),
            find_clipping(np.minimum(u * 2.5, 65535).astype(np.uint16)),
        )

    print(f"clipping test over {args.n} random cases per family (seed {args.seed})")
    print(f"{'family':42s} {'false alarms':>13s} {'detected':>9s}")
    for name, (n, fa, det) in sorted(counts.items()):
        print(f"{name:42s} {fa / n:12.1%} {det / n:9.1%}   (n = {n})")


if __name__ == "__main__":
    main()
