"""Siemens-star and bar-target accuracy (issue 10): satchain vs the simple methods it replaced, same run.

Targets are rendered independently of satchain.measure by the tests' exact renderers
(tests/measure/test_star.py: sinusoidal star, isotropic blur, 4 x 4 sub-pixel integration;
tests/measure/test_bars.py: bars on a plate, Gaussian PSF x pixel box, exact CDF at pixel centres).

Star: centre NOT given (star on a pixel centre, 1/32 px and 1/2 px from one, then off the region centre by
up to 1.5 px), input modulation not given; printed:
max |MTF error| up to Nyquist over the four directions, for satchain (centre estimated, log-quadratic
extrapolation of the input modulation) and the reference (region centre, straight-line extrapolation of
the outer radii: the previous default), and their ratio.
Star on the pixel lattice: centres at every (dx, dy) in {0, 1/32, 1/4, 1/2} px from a pixel centre, centre
given exactly and input modulation 0.4 given (the annulus fits alone); printed per MTF: max |MTF error| up to
Nyquist over the 16 centres and four directions, for satchain (amplitude quadratic across 3-px bands) and the
reference (constant amplitude per 1-px annulus, the previous fit), and their ratio.
Bars: 3-bar groups at 16 sub-pixel phases; printed: max |CTF - Coltman| for satchain's fit at the known
period (the group alone, and in a target with 12, 5, 4, 3 px groups whose joint MTF fills harmonics the group
cannot observe) and for the sampled (max - min) of the reference, and their ratio (reference / in target).

Run:  PYTHONPATH=src python benchmarks/bench_targets.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from test_bars import _coltman, _group  # noqa: E402
from test_star import DIRS, MTFS, _render_star, _truth  # noqa: E402

from satchain.measure._starfit import annulus_fit  # noqa: E402
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
        lattice = [(0.0, 0.0), (0.0, 1 / 32), (0.0, 0.5)]  # centres on / near a pixel centre, then random
        for dx, dy in lattice + [tuple(rng.uniform(-1.5, 1.5, 2)) for _ in range(n_cases // 2)]:
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


def _constant_amplitude_mtf(img, n, xc, yc, r_in, r_out, m0):
    """Previous fit: constant amplitude per 1-px annulus |r - r_k| <= 0.5 (per pair of 45-deg sectors)."""
    y, x = np.mgrid[0 : img.shape[0], 0 : img.shape[1]]
    rr, th, v = np.hypot(x - xc, y - yc).ravel(), np.arctan2(y - yc, x - xc).ravel(), img.ravel()
    radii = np.arange(r_out - 0.5, r_in, -1.0)
    out = {k: np.full(radii.size, np.nan) for k in DIRS}
    for i, r in enumerate(radii):
        sel = np.abs(rr - r) <= 0.5
        t, val = th[sel], v[sel]
        for k, a in DIRS.items():
            m = np.abs(np.angle(np.exp(2j * (t - np.deg2rad(a + 90))))) / 2 <= np.pi / 8
            a0, amp, *_ = annulus_fit(t[m], val[m], n)
            out[k][i] = amp / a0 / m0
    return n / (2 * np.pi * radii), out


def star_lattice_errors() -> None:
    print("\nSiemens star centred on / near a pixel centre (centre and input modulation given): max |MTF error|")
    print(f"{'MTF':>9} {'satchain':>9} {'reference':>9} {'ratio':>6}")
    offs = (0.0, 1 / 32, 0.25, 0.5)
    for kind, mtf in MTFS.items():
        errs = [0.0, 0.0]
        for dx in offs:
            for dy in offs:
                c = (60 + dx, 60 + dy)
                img = _render_star(32, c, mtf)
                r = measure_star(img, cycles=32, center=c, refine_center=False, input_modulation=0.4)
                f_ref, ref = _constant_amplitude_mtf(img, 32, *c, 32 / (2 * np.pi * 0.75), r.radius_px.max() + 0.5, 0.4)
                for j, (f, m) in enumerate(((r.f_cy_per_px, r.mtf), (f_ref, ref))):
                    ok = f <= 0.5
                    e = max(np.nanmax(np.abs(m[k] - _truth(f, mtf, a))[ok]) for k, a in DIRS.items())
                    errs[j] = max(errs[j], e)
        print(f"{kind:>9} {errs[0]:9.4f} {errs[1]:9.4f} {errs[1] / errs[0]:6.1f}")


def _in_target(period, phase, sigma):
    """The group followed by groups of 12, 5, 4 and 3 px (one target, one MTF): CTF error of the group."""
    periods = (period, 12.0, 5.0, 4.0, 3.0)
    blocks, rois, x0 = [], [], 0
    for p, ph in zip(periods, (phase, 0.3, 0.7, 0.1, 0.45), strict=True):
        img, roi = _group(p, ph, 3, sigma)
        blocks.append(img)
        rois.append((roi[0] + x0, 0, roi[2] + x0, img.shape[0]))
        x0 += img.shape[1]
    r = measure_bars(np.hstack(blocks), periods_px=periods, group_rois=rois, levels=(40.0, 160.0))
    return abs(r.ctf[0] - _coltman(1 / period, sigma))


def bar_errors(sigma: float) -> None:
    print(f"\n3-bar groups, Gaussian PSF sigma {sigma} px x pixel, 16 phases: max |CTF - Coltman|")
    print("(alone: the group measured on its own; in target: with 12, 5, 4, 3 px groups, joint MTF model)")
    print(f"{'period px':>9} {'alone':>9} {'in target':>9} {'sampled':>9} {'ratio':>6}  flags (alone)")
    for period in (2.5, 3.0, 3.3, 4.0, 5.0, 6.0, 7.5, 8.0, 10.0, 12.0):
        fit_err, joint_err, ref_err, flagged = 0.0, 0.0, 0.0, False
        for phase in np.linspace(0, 1, 16, endpoint=False):
            img, roi = _group(period, phase, 3, sigma)
            r = measure_bars(img, periods_px=[period], group_rois=[roi], levels=(40.0, 160.0))
            prof = img[0, roi[0] : roi[2]]
            sampled = (prof.max() - prof.min()) / (prof.max() + prof.min()) / 0.6
            truth = _coltman(1 / period, sigma)
            fit_err = max(fit_err, abs(r.ctf[0] - truth))
            joint_err = max(joint_err, _in_target(period, phase, sigma))
            ref_err = max(ref_err, abs(sampled - truth))
            flagged |= any("alias" in f for f in r.flags)
        ratio = ref_err / max(joint_err, 1e-6)
        print(
            f"{period:9.2f} {fit_err:9.4f} {joint_err:9.4f} {ref_err:9.4f} {ratio:6.1f}  "
            f"{'aliasing flagged' if flagged else ''}"
        )


if __name__ == "__main__":
    star_errors()
    star_lattice_errors()
    for s in (0.4, 0.6, 0.8):
        bar_errors(s)
