"""Slanted-edge audit cases of issue 18 point 7, on exact Gaussian-PSF edges integrated over the pixel area.

Edges come from tests/measure/_render_audit.py (ESF = Phi(d / sigma) averaged over 16 x 16 points of each
pixel; curved edges are circles of radius R); the truth along the normal is
exp(-2 pi^2 sigma^2 f^2) |sinc(f cos t) sinc(f sin t)| (averaged over the local angles of a circle).

Printed:
  curvature   R 500-3000 px in a 100 px region (tilt 5 deg, sigma 0.4 px, noise-free): max |error| up to
              Nyquist of a forced straight fit, whether it is flagged (curvature_bias) and the shift the flag
              states; the automatic degree's error and flags.
  low SNR     40 edges of 100 x 60 px per row, contrast 0.5, noise 0.005 / 0.01 (SNR 100 / 50), sigma
              0.6-1.0 px, tilt 2-12 deg, random phase: mean error and the fraction of |error| < 2 sigma at
              0.1, 0.15 and 0.5 cy/px.
  8-bit       uint8 edges 100 -> 100 + L DN (sigma 0.5 px, noise-free): error at Nyquist, flag; and the
              evidence for the flag's threshold: the largest MTF error up to Nyquist of the quantised edge
              against the same float edge, over 3 PSFs x 4 tilts/phases, versus the step count L.

Run:  python benchmarks/bench_edge_audit.py                      (about 1 min)
      python benchmarks/bench_edge_audit.py --compare /work/main/src   (also runs another checkout's code,
                                                                         side by side: before | after)
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render_audit import render_gauss_edge, truth_mtf  # noqa: E402

F = np.arange(0.0, 0.5001, 0.005)


def _curve_truth(angle, sigma, radius, n):
    y = np.arange(n) - (n - 1) / 2
    return np.mean([truth_mtf(F, angle + np.degrees(np.arcsin(v / radius)), sigma) for v in y], axis=0)


def _stated_shift(r):
    import re

    if "curvature_bias" not in r.flags:
        return None
    m = re.search(r"moves the MTF by ([0-9.]+)", r.warnings[r.flags.index("curvature_bias")])
    return float(m.group(1)) if m else None


def curvature_cases(measure_edge):
    out = []
    for radius in (500.0, 1000.0, 2000.0, 3000.0):
        img = 0.1 + 0.8 * render_gauss_edge((100, 100), 5.0, sigma_px=0.4, phase_px=0.21, radius_px=radius)
        truth = _curve_truth(5.0, 0.4, radius, 100)
        r1, ra = measure_edge(img, fit_degree=1), measure_edge(img)
        e1 = float(np.max(np.abs(np.interp(F, r1.f_cy_per_px, r1.mtf) - truth)))
        ea = float(np.max(np.abs(np.interp(F, ra.f_cy_per_px, ra.mtf) - truth)))
        out.append(
            dict(
                radius=radius,
                err_deg1=e1,
                flag_deg1="curvature_bias" in r1.flags,
                stated=_stated_shift(r1),
                err_auto=ea,
                deg_auto=ra.fit_degree,
                flag_auto="curvature_bias" in ra.flags,
            )
        )
    return out


def low_snr_cases(measure_edge, n=40):
    fs = np.array([0.1, 0.15, 0.5])
    out = []
    for sigma in (0.6, 0.8, 1.0):
        for noise in (0.005, 0.01):
            rng = np.random.default_rng(int(1000 * sigma + 1e5 * noise))
            err, sig = [], []
            for _ in range(n):
                angle = rng.uniform(2, 12)
                img = 0.25 + 0.5 * render_gauss_edge((100, 60), angle, sigma_px=sigma, phase_px=rng.uniform(-0.5, 0.5))
                r = measure_edge(img + rng.normal(0, noise, img.shape))
                err.append(np.interp(fs, r.f_cy_per_px, r.mtf) - truth_mtf(fs, angle, sigma))
                sig.append(np.interp(fs, r.f_cy_per_px, r.mtf_sigma))
            err, sig = np.array(err), np.array(sig)
            out.append(
                dict(
                    sigma=sigma,
                    snr=0.5 / noise,
                    bias=err.mean(axis=0).tolist(),
                    cover=np.mean(np.abs(err) < 2 * sig, axis=0).tolist(),
                )
            )
    return out


def eight_bit_cases(measure_edge):
    out = []
    for levels in (10, 20, 40, 80, 150):
        v = 100 + levels * render_gauss_edge((100, 100), 5.0, sigma_px=0.5, phase_px=0.21)
        r = measure_edge(np.round(v).astype(np.uint8))
        truth = float(truth_mtf(0.5, 5.0, 0.5))
        out.append(dict(levels=levels, rel_err=(r.mtf_at_nyquist - truth) / truth, flag="quantisation" in r.flags))
    return out


def quantisation_evidence(measure_edge):
    """Largest |MTF(quantised) - MTF(float)| up to Nyquist, noise-free, vs the step count."""
    rng = np.random.default_rng(7)
    out = []
    for levels in (8, 16, 24, 32, 48, 64, 96, 128):
        worst = []
        for sigma in (0.35, 0.5, 0.65):
            for _ in range(4):
                v = 100 + levels * render_gauss_edge(
                    (100, 100), rng.uniform(2, 12), sigma_px=sigma, phase_px=rng.uniform(-0.5, 0.5)
                )
                rq, rf = measure_edge(np.round(v).astype(np.uint8)), measure_edge(v)
                d = np.interp(F, rq.f_cy_per_px, rq.mtf) - np.interp(F, rf.f_cy_per_px, rf.mtf)
                worst.append(float(np.max(np.abs(d))))
        out.append(dict(levels=levels, mean=float(np.mean(worst)), max=float(np.max(worst))))
    return out


def run_all():
    from satchain.measure.edge import measure_edge

    return dict(
        curvature=curvature_cases(measure_edge),
        low_snr=low_snr_cases(measure_edge),
        eight_bit=eight_bit_cases(measure_edge),
        evidence=quantisation_evidence(measure_edge),
    )


def _pair(before, after, fmt):
    a = fmt(after)
    return a if before is None else f"{fmt(before):>14} | {a}"


def show(after, before=None):
    b = before or {}
    head = "before | after" if before else ""
    print(f"curvature: forced straight fit, 100 px region, tilt 5 deg, sigma 0.4 px   {head}")
    for i, c in enumerate(after["curvature"]):
        cb = b["curvature"][i] if before else None

        def deg1(c):
            flag = f"flag (states {c['stated']:.3f})" if c["flag_deg1"] else "no flag"
            return f"err {c['err_deg1']:.3f} {flag}"

        def auto(c):
            return f"err {c['err_auto']:.4f} deg {c['deg_auto']}{' FLAG' if c['flag_auto'] else ''}"

        print(f"  R {c['radius']:5.0f} px  fit_degree=1: {_pair(cb, c, deg1)}")
        print(f"            auto:         {_pair(cb, c, auto)}")
    print(f"\nlow SNR: 40 edges 100 x 60 px each, bias | 2-sigma coverage at 0.1, 0.15, 0.5 cy/px   {head}")
    for i, c in enumerate(after["low_snr"]):
        cb = b["low_snr"][i] if before else None

        def row(c):
            bias = " ".join(f"{v:+.4f}" for v in c["bias"])
            cov = " ".join(f"{100 * v:3.0f}%" for v in c["cover"])
            return f"{bias}  {cov}"

        print(f"  sigma {c['sigma']:.1f} SNR {c['snr']:3.0f}: {_pair(cb, c, row)}")
    print(f"\n8-bit: uint8 100 -> 100+L DN, noise-free, sigma 0.5 px: relative error at Nyquist, flag   {head}")
    for i, c in enumerate(after["eight_bit"]):
        cb = b["eight_bit"][i] if before else None
        print(
            f"  L {c['levels']:4d}: "
            + _pair(cb, c, lambda c: f"{100 * c['rel_err']:+6.1f} % {'quantisation' if c['flag'] else 'no flag'}")
        )
    print("\nquantisation threshold evidence: max |MTF(uint8) - MTF(float)| up to Nyquist (12 edges per L)")
    for c in after["evidence"]:
        print(f"  L {c['levels']:4d}: mean {c['mean']:.4f}  max {c['max']:.4f}  max x L = {c['max'] * c['levels']:.2f}")
    print("  -> flagged below 65 levels (0.65 / L > 0.01) unless the noise dithers the steps (>= 0.45 step rms)")


def main(argv):
    if "--json" in argv:
        print(json.dumps(run_all()))
        return
    before = None
    if "--compare" in argv:
        src = argv[argv.index("--compare") + 1]
        env = dict(os.environ, PYTHONPATH=src)
        res = subprocess.run([sys.executable, __file__, "--json"], env=env, capture_output=True, text=True, check=True)
        before = json.loads(res.stdout)
    show(run_all(), before)


if __name__ == "__main__":
    main(sys.argv[1:])
