"""Siemens-star and bar-target accuracy (issue 10): satchain vs the simple methods it replaced, same run.

Targets are rendered independently of satchain.measure by the tests' exact renderers
(tests/measure/test_star.py: sinusoidal star, isotropic blur, 4 x 4 sub-pixel integration;
tests/measure/test_bars.py: bars on a plate, Gaussian PSF x pixel box, exact CDF at pixel centres).

Star: centre NOT given (star off the region centre by up to 1.5 px), input modulation not given; printed:
max |MTF error| up to Nyquist over the four directions, for satchain (centre estimated, log-quadratic
extrapolation of the input modulation) and the reference (region centre, straight-line extrapolation of
the outer radii: the previous default), and their ratio.
Bars: 3-bar groups at 16 sub-pixel phases; printed: max |CTF - Coltman| for satchain's fit at the known
period and for the sampled (max - min) of the reference, and their ratio.

Run:  PYTHONPATH=src python benchmarks/bench_targets.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from test_bars import _coltman, _group  # noqa: E402
from test_star import DIRS, MTFS, _render_star, _truth  # noqa: E402

from satchain.measure.bars import measure_bars  # noqa: E402
from satchain.measure.star import measure_star  # noqa: E402


def _straight_line_m0(r) -> float:
    """Previous default: straight line through the outer radii (f <= 2.5 f_min) extrapolated to f = 0."""
    f, m = r.f_cy_per_px, r.mtf_all * r.input_modulation
    low = f <= 2.5 * f.min()
    slope, icpt = np.polyfit(f[low], m[low], 1)
    return float(icpt) if slope <= 0 else float(np.median(m[low]))


def star_errors(n_cases: int = 8, seed: int = 0) -> None:
    rng = np.random.default_rng(seed)
    print("Siemens star, 32 cycles, 121 x 121 px, centre and input modulation not given")
    print(f"{'MTF':>9} {'offset px':>15} {'satchain':>9} {'reference':>9} {'ratio':>6}")
    for kind, mtf in MTFS.items():
        for _ in range(n_cases // 2):
            dx, dy = rng.uniform(-1.5, 1.5, 2)
            img = _render_star(32, (60 + dx, 60 + dy), mtf)
            r = measure_star(img, cycles=32)
            first = measure_star(img, cycles=32, refine_center=False, input_modulation=1.0)
            ref = measure_star(img, cycles=32, refine_center=False, input_modulation=_straight_line_m0(first))
            errs = []
            for res in (r, ref):
                ok = res.f_cy_per_px <= 0.5
                errs.append(
                    max(np.max(np.abs(res.mtf[k] - _truth(res.f_cy_per_px, mtf, a))[ok]) for k, a in DIRS.items())
                )
            print(f"{kind:>9} {dx:+7.2f},{dy:+7.2f} {errs[0]:9.4f} {errs[1]:9.4f} {errs[1] / errs[0]:6.1f}")


def bar_errors(sigma: float) -> None:
    print(f"\n3-bar groups, Gaussian PSF sigma {sigma} px x pixel, 16 phases: max |CTF - Coltman|")
    print(f"{'period px':>9} {'satchain':>9} {'sampled':>9} {'ratio':>6}  flags")
    for period in (2.5, 3.0, 3.3, 4.0, 5.0, 6.0, 7.5, 8.0, 10.0, 12.0):
        fit_err, ref_err, flagged = 0.0, 0.0, False
        for phase in np.linspace(0, 1, 16, endpoint=False):
            img, roi = _group(period, phase, 3, sigma)
            r = measure_bars(img, periods_px=[period], group_rois=[roi], levels=(40.0, 160.0))
            prof = img[0, roi[0] : roi[2]]
            sampled = (prof.max() - prof.min()) / (prof.max() + prof.min()) / 0.6
            truth = _coltman(1 / period, sigma)
            fit_err = max(fit_err, abs(r.ctf[0] - truth))
            ref_err = max(ref_err, abs(sampled - truth))
            flagged |= any("alias" in f for f in r.flags)
        ratio = ref_err / max(fit_err, 1e-6)
        print(f"{period:9.2f} {fit_err:9.4f} {ref_err:9.4f} {ratio:6.1f}  {'aliasing flagged' if flagged else ''}")


if __name__ == "__main__":
    star_errors()
    for s in (0.4, 0.6, 0.8):
        bar_errors(s)
