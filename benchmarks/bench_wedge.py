"""Wedge prediction benchmark (issue 18): measured vs predicted wedge contrast and resolution in a run.

For each wedge of a run (default: the default run, the paper's scene and camera) it prints the measured and
predicted resolution (the prediction: the same scan and 15 % crossing on the wedge's noise-free predicted
image), the crossing's 1-sigma from noise (parametric bootstrap) and the measurement's own estimate, the
prediction's spread over sub-pixel placements, and the largest contrast residual where the lines are wider
than 2 GSD (and 0.6 m) against the modelled prediction and against Coltman's CTF of an infinite square wave
(the prediction before issue 18), with the reflectance modulation 0.88 applied to it for comparison.

    python benchmarks/bench_wedge.py                    # the default run (~20 s)
    python benchmarks/bench_wedge.py --config run.toml  # e.g. [as_built] motion = { smear_px = 3.0 }
    python benchmarks/bench_wedge.py --seeds 10 --config run.toml   # seed-to-seed spread of the crossing
"""

from __future__ import annotations

import argparse

import numpy as np

import satchain
from satchain.config.run import RunConfig, load_run_config
from satchain.tf import ctf as ctf


def _wedge_rows(result) -> None:
    p = result.predictions
    for w in result.comparison.hyperbolic_wedge:
        lw, c = np.asarray(w.line_width_m, float), np.asarray(w.contrast, float)
        cp = np.asarray([np.nan if v is None else v for v in w.contrast_predicted], float)
        col = np.asarray(ctf.coltman_ctf(w.gsd_m / (2 * lw), p.mtf_along[w.axis]), float)
        it = next(i for i in result.scene.truth["items"] if i["id"] == w.id)
        mod = (it["bright"] - it["dark"]) / (it["bright"] + it["dark"])
        print(f"wedge {w.id} ({w.axis})")
        print(
            f"  resolution measured {w.resolution_m:.4f} m  predicted {w.resolution_predicted_m:.4f} m  "
            f"relative error {w.relative_error:+.4f}  sigma {w.relative_error_sigma:.4f}  "
            f"({'pass' if w.passed else 'FAIL'})"
        )
        print(
            f"  crossing 1-sigma: noise bootstrap {w.resolution_m_std * 1e3:.2f} mm, measure's estimate "
            f"{w.resolution_m_std_measure * 1e3:.1f} mm; prediction over placements {w.resolution_predicted_m_std * 1e3:.1f} mm "  # noqa: E501
            f"{[None if v is None else round(v, 4) for v in w.resolution_predicted_by_placement_m]}"
        )
        for name, sel in (("lines > 2 GSD", lw > 2 * w.gsd_m), ("lines > 0.6 m", lw > 0.6)):
            if not sel.any():
                continue
            print(
                f"  {name} ({sel.sum()} positions): max |measured - modelled| {np.max(np.abs(c - cp)[sel]):.4f}, "
                f"max |measured - Coltman| {np.max(np.abs(c - col)[sel]):.4f} (mean {np.mean((c - col)[sel]):+.4f}), "
                f"max |measured - {mod:.3f} Coltman| {np.max(np.abs(c - mod * col)[sel]):.4f} "
                f"(mean {np.mean((c - mod * col)[sel]):+.4f})"
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=None, help="run configuration TOML (default: the default run)")
    ap.add_argument("--seeds", type=int, default=0, help="also run this many seeds and print the spread")
    a = ap.parse_args()
    cfg = load_run_config(a.config)
    result = satchain.run(cfg)
    print(result.comparison)
    _wedge_rows(result)
    if a.seeds:
        res: dict[str, list] = {}
        for seed in range(1, a.seeds + 1):
            d = {**cfg.to_dict(), "simulation": {**cfg.to_dict()["simulation"], "seed": seed}}
            r = satchain.run(RunConfig.from_dict(d, base_dir=cfg.base_dir))
            for w in r.comparison.hyperbolic_wedge:
                res.setdefault(w.id, []).append((w.resolution_m, w.resolution_m_std, w.resolution_m_std_measure))
        for k, v in res.items():
            v = np.asarray(v, float)
            print(
                f"{k}: {len(v)} seeds, crossing spread {np.std(v[:, 0], ddof=1) * 1e3:.2f} mm; mean bootstrap "
                f"1-sigma {v[:, 1].mean() * 1e3:.2f} mm; mean measure's estimate {v[:, 2].mean() * 1e3:.1f} mm"
            )


if __name__ == "__main__":
    main()
