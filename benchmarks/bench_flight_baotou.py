"""Baotou-like flight crops (issue 19): `measure find` with defaults (the AOI zero fill is excluded on evidence).

Prints, over N renders (rotation 10-20 deg, random grid phase and noise), the error of the combined ACT/ALT MTF
at Nyquist against the exact truth, the error of the joined edge angles (and of each half's own angle), and the
per-edge MTF at Nyquist of the joined halves measured on their own fitted line (before) and on the joint line
(after, what `measure find` reports).  ``--no-noise`` renders without noise (quantised to uint16, measured with
defaults too: the fill is found without noise), where the line's accuracy is not hidden by the noise.

    PYTHONPATH=src python benchmarks/bench_flight_baotou.py [N]
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render_baotou import render_baotou, truth_mtf  # noqa: E402

from satchain.measure.find_mtf import measure_found_edges  # noqa: E402


def _stats(v) -> str:
    v = np.asarray(v, dtype=float)
    return f"mean {np.mean(v):+.4f} rms {np.sqrt(np.mean(v**2)):.4f} max {np.abs(v).max():.4f}"


def main(n: int = 20, noise: bool = True) -> None:
    rng = np.random.default_rng(19)
    mtf_err, ang_err, own_ang_err, own_err, joint_err, found = [], [], [], [], [], 0
    for seed in range(n):
        ang = rng.uniform(10, 20)
        img, valid = render_baotou(angle_deg=ang, phase=tuple(rng.uniform(-0.5, 0.5, 2)), seed=seed if noise else None)
        img = img if noise else np.round(img).astype(np.uint16)
        res = measure_found_edges(img)  # defaults: the zero fill is found on evidence, with or without noise
        found += any("taken as nodata" in f for f in res.flags)
        t = truth_mtf(0.5, ang)
        mtf_err += [res.combined[d].mtf_at_nyquist - t for d in ("ACT", "ALT")]
        for e in res.edges:
            true = -ang if e.direction == "ACT" else 90 - ang
            ang_err.append(e.angle_deg - true)
            if e.joined_with is not None:
                own_ang_err.append(e.own_angle_deg - true)
                own_err.append(e.own_mtf_at_nyquist - t)
                joint_err.append(e.mtf_at_nyquist - t)
    a, o = np.abs(ang_err), np.abs(own_ang_err)
    print(f"{n} images ({'noise' if noise else 'no noise'}), the zero fill found in {found}: "
          f"combined MTF@Nyq error {_stats(mtf_err)}")  # fmt: skip
    print(f"angle error (joined halves): rms {np.sqrt(np.mean(a**2)):.3f} deg, max {a.max():.3f} deg; "
          f"each half's own fit: rms {np.sqrt(np.mean(o**2)):.3f} deg, max {o.max():.3f} deg")  # fmt: skip
    print(f"{len(joint_err)} joined halves, MTF@Nyq error on their own line:  {_stats(own_err)}")
    print(f"{len(joint_err)} joined halves, MTF@Nyq error on the joint line: {_stats(joint_err)}")
    d = np.abs(joint_err) - np.abs(own_err)
    print(f"|error| joint - own: mean {d.mean():+.4f} +- {d.std(ddof=1) / np.sqrt(d.size):.4f} (standard error)")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(int(args[0]) if args else 20, noise="--no-noise" not in sys.argv)
