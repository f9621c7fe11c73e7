"""The Siemens-star check before and after its prediction was measured (issue 18).

Before: the prediction was the system MTF along each direction and sigma the measured 1-sigma at the point of
largest |error| (so the estimator's own bias, ~0.02 at the star's outer radii, sat in the error as z ~ +17).
After: the prediction is the star measured on its noise-free predicted image (satchain.prediction.star), the
error the signed largest difference, sigma that of the largest of the compared points' errors.

Prints, for the default run (the paper scene, ankarasat3): the star row before and after, the estimator's
systematic; then the same over the noise of several seeds (the image re-noised, the rest of the run kept);
and the time the star prediction adds to a run.

Run: ``PYTHONPATH=$PWD/src python benchmarks/bench_star_prediction.py [--seeds 8]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import satchain
from satchain.comparison import compare
from satchain.config.run import RunConfig


def _before(s) -> tuple[float, float | None]:
    """(signed largest measured - system MTF over 0.05..0.5 cy/px, the measured 1-sigma there): the old check."""
    best = (0.0, None)
    f = np.asarray(s.f_cy_per_px, float)
    band = (f >= 0.05) & (f <= 0.5)
    for d, curve in s.mtf_measured.items():
        e = np.asarray(curve, float) - np.asarray(s.directions[d]["mtf_model"], float)
        ok = band & np.isfinite(e)
        if not ok.any():
            continue
        i = np.flatnonzero(ok)[np.argmax(np.abs(e[ok]))]
        if abs(e[i]) > abs(best[0]):
            sd = s.mtf_std_measured.get(d)
            best = (float(e[i]), None if sd is None else float(sd[i]))
    return best


def _line(label: str, err: float, sig: float | None) -> str:
    z = "-" if not sig else f"{err / sig:+6.2f}"
    return f"  {label:<40} error {err:+.4f}  sigma {sig if sig is None else round(sig, 4)!s:>7}  z {z}"


def _star_rows(result) -> tuple:
    (row,) = [r for r in result.comparison.rows if r.kind == "star_mtf"]
    return row, result.comparison.siemens_star[0]


def _seeds(result, n: int) -> None:
    from satchain.engine.sources import SceneSource
    from satchain.measure.auto import measure_auto

    sim, sc = result.simulation, result.scene
    src = SceneSource(sc.scene, pixel_m=sc.pixel_m)
    coarse = sim.simulator.decimate(src)
    star_ids = [s.id for s in result.comparison.siemens_star]
    z_before, z_after = [], []
    for seed in range(1, n + 1):
        img = sim.simulator.run(src, sensor=sim.sensor, units=sim.units, noise=True, seed=seed, coarse=coarse)
        auto = measure_auto(img, sc.truth_dict, pixel_m=result.system.gsd_act_m, ids=star_ids)
        c = compare({"siemens_star": auto.to_dict()["siemens_star"]}, result.predictions, result.config.tolerances)
        (row,) = [r for r in c.rows if r.kind == "star_mtf"]
        eb, sb = _before(c.siemens_star[0])
        z_before.append(eb / sb if sb else np.nan)
        z_after.append(row.z)
        print(f"  seed {seed:2d}: before z {z_before[-1]:+6.2f}   after error {row.error:+.4f} sigma {row.sigma:.4f} "
              f"z {row.z:+5.2f}")  # fmt: skip
    zb, za = np.asarray(z_before), np.asarray(z_after)
    print(f"  over {n} seeds: before z mean {np.nanmean(zb):+.2f} (std {np.nanstd(zb, ddof=1):.2f});"
          f"  after z mean {za.mean():+.2f}, std {za.std(ddof=1):.2f}")  # fmt: skip


def _timing(result) -> None:
    from satchain.prediction.core import WIDE_COMPONENTS, _SystemOTF
    from satchain.prediction.star import predict_stars

    otf = result.budget.otf
    otf2d = _SystemOTF(otf, tuple(c for c in WIDE_COMPONENTS if c in otf.component_names))
    truth = result.scene.truth_dict
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        predict_stars(otf2d, truth, gsd_m=result.system.gsd_m)
        times.append(time.perf_counter() - t0)
    print(f"  the star prediction adds {min(times):.2f} s to a run (best of 3; compare stage in this run: "
          f"{result.timings_s.get('compare', float('nan')):.2f} s)")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=8, help="noise seeds to re-measure the star with")
    args = ap.parse_args()
    t0 = time.perf_counter()
    result = satchain.run(RunConfig())
    print(f"default run (in memory): {time.perf_counter() - t0:.1f} s")
    row, s = _star_rows(result)
    eb, sb = _before(s)
    print("star check, default run (seed 20260101):")
    print(_line("before (system MTF, sigma at the worst):", eb, sb))
    print(_line("after (noise-free predicted measurement):", row.error, row.sigma))
    print(f"  after: measured {row.measured:.4f}, predicted {row.predicted:.4f}, system MTF {row.model_prediction:.4f}"
          f" at {s.worst_direction} {s.worst_f_cy_per_px:.3f} cy/px")  # fmt: skip
    print(f"  estimator systematic (predicted - system MTF): largest {s.estimator_systematic:+.4f} "
          f"({s.estimator_systematic_direction}, {s.estimator_systematic_f_cy_per_px:.3f} cy/px)")  # fmt: skip
    print(f"  prediction: {s.prediction}")
    _timing(result)
    if args.seeds > 0:
        print(f"star check over {args.seeds} noise seeds (the same noise-free image re-noised):")
        _seeds(result, args.seeds)


if __name__ == "__main__":
    main()
