"""A smear sweep over one edge image: the cost of a case against a plain simulate_file call, and the physics.

An N x N float reflectance image of a straight edge across the rows (exact area coverage, at 4 input pixels per
GSD) is swept over ``motion.smear_px`` with :func:`satchain.engine.sweep.simulate_sweep` (reflectance, no noise),
then the same cases again as plain :func:`simulate_file` calls. Printed per case: the along-track (ALT) edge
sharpness (largest step between neighbouring rows over the whole step: 1 is a perfect edge; it must fall as the
smear grows), and overall: seconds per case in the sweep and alone (the sweep's overhead: validation and the
manifest), and the largest difference between the 3 px smear and the 1 px smear averaged over shifts of
-1, 0, +1 px (a closed form: a box of 3 px is a box of 1 px at three offsets).

Run:  python benchmarks/bench_sweep.py [--n 512]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from satchain import io, load_preset  # noqa: E402
from satchain.engine.files import simulate_file  # noqa: E402
from satchain.engine.sweep import simulate_sweep  # noqa: E402

SMEARS = [0.0, 0.5, 1.0, 2.0, 3.0, 4.0]


def _edge(n: int) -> np.ndarray:
    cover = np.clip(np.arange(n) + 1 - (n / 2 - 0.7), 0.0, 1.0)
    return np.repeat((0.1 + 0.5 * cover)[:, None], n, axis=1).astype(np.float32)


def _sharpness(image: np.ndarray) -> float:
    prof = image[:, 4:-4].mean(axis=1)
    return float(np.max(np.diff(prof)) / (prof[-4:].mean() - prof[:4].mean()))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=512)
    n = ap.parse_args().n
    system = load_preset("ankarasat3")
    with tempfile.TemporaryDirectory() as d:
        src = Path(d) / "edge.tif"
        io.write_tiff(src, _edge(n), pixel_m=system.gsd_act_m / 4)
        simulate_file(src, Path(d) / "warm.tif", system, units="reflectance", noise=False)  # imports, caches
        t0 = time.perf_counter()
        cases = simulate_sweep([src], system, Path(d) / "out", sweep={"motion.smear_px": SMEARS},
                               units="reflectance", noise=False)  # fmt: skip
        t_sweep = (time.perf_counter() - t0) / len(cases)
        t0 = time.perf_counter()
        for i, c in enumerate(cases):
            simulate_file(src, Path(d) / f"alone{i}.tif", system.replace(c.parameters), units="reflectance",
                          noise=False)  # fmt: skip
        t_alone = (time.perf_counter() - t0) / len(cases)
        images = [io.read_image(c.image)[0].astype(float) for c in cases]
    print(f"{n} x {n} input px -> {cases[0].shape_px[0]} x {cases[0].shape_px[1]} px, {len(cases)} cases")
    for c, a in zip(cases, images, strict=True):
        print(f"  motion.smear_px = {c.parameters['motion.smear_px']:<4g} ALT edge sharpness {_sharpness(a):.4f}")
    one, three = images[SMEARS.index(1.0)], images[SMEARS.index(3.0)]
    err = np.abs(three[4:-4] - (one[3:-5] + one[4:-4] + one[5:-3]) / 3).max()
    print(f"seconds per case: sweep {t_sweep:.3f}, simulate_file alone {t_alone:.3f} (ratio {t_sweep / t_alone:.2f})")
    print(f"smear 3 px vs 1 px averaged over -1, 0, +1 px: max difference {err:.2e} (float32 storage)")


if __name__ == "__main__":
    main()
