"""Baotou-like flight crops (issue 19): `measure find` with defaults (the AOI zero fill is excluded on evidence).

Prints, over N renders (rotation 10-20 deg, random grid phase and noise), the error of the combined ACT/ALT MTF
at Nyquist against the exact truth and the error of the joined edge angles.

    PYTHONPATH=src python benchmarks/bench_flight_baotou.py [N]
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render_baotou import render_baotou, truth_mtf  # noqa: E402

from satchain.measure.find_mtf import measure_found_edges  # noqa: E402


def main(n: int = 20) -> None:
    rng = np.random.default_rng(19)
    mtf_err, ang_err = [], []
    for seed in range(n):
        ang = rng.uniform(10, 20)
        img, _ = render_baotou(angle_deg=ang, phase=tuple(rng.uniform(-0.5, 0.5, 2)), seed=seed)
        res = measure_found_edges(img)  # defaults: the zero fill is found on evidence
        mtf_err += [res.combined[d].mtf_at_nyquist - truth_mtf(0.5, ang) for d in ("ACT", "ALT")]
        ang_err += [e.angle_deg - (-ang if e.direction == "ACT" else 90 - ang) for e in res.edges]
    m, a = np.abs(mtf_err), np.abs(ang_err)
    print(f"{n} images: MTF@Nyq error mean {np.mean(mtf_err):+.4f} rms {np.sqrt(np.mean(m**2)):.4f} max {m.max():.4f}")
    print(f"angle error (joined halves): rms {np.sqrt(np.mean(a**2)):.3f} deg, max {a.max():.3f} deg")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
