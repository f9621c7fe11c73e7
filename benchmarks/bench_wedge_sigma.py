"""Wedge noise estimate and crossing 1-sigma, before (main) and after issue 18's fix, on exact renders.

Converging-line wedges are rendered exactly (tests/measure/_render_wedge.py: the pixel integral of a square
wave of stripe width w(x), optionally erf-blurred), hyperbolic and linear, sharp and blurred, with Gaussian
noise of sigma (stripes 0.2 / 0.8). For each case it prints

* the noise estimate over the true sigma (noise-free: the estimate itself, and whether the wedge is refused);
* over ``--seeds`` noise realisations: the crossing's mean error against the noise-free image's crossing
  (line width, px), the scatter of the crossing, the mean reported 1-sigma, scatter / mean sigma, and the
  coverage (fraction with |error| < 2 sigma).

"before" is ``measure_wedge`` of ``git show main:src/satchain/measure/wedge.py`` (``--before REF``), run from a
temporary module; "after" the working tree's.

    python benchmarks/bench_wedge_sigma.py              # ~1 min
    python benchmarks/bench_wedge_sigma.py --seeds 10 --before main
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "measure"))
from _render_wedge import hyperbolic, linear, render_wedge, widths_at_columns  # noqa: E402

from satchain.errors import InputError  # noqa: E402
from satchain.measure.wedge import measure_wedge as after  # noqa: E402

CASES = [
    ("hyperbolic sharp", hyperbolic(4.0, 30.0), 0.0),
    ("hyperbolic blur 0.5", hyperbolic(4.0, 30.0), 0.5),
    ("hyperbolic blur 1.0", hyperbolic(4.0, 30.0), 1.0),
    ("linear sharp", linear(3.0, 0.015), 0.0),
    ("linear blur 0.7", linear(3.0, 0.015), 0.7),
]


def _load_before(ref: str):
    src = subprocess.run(["git", "-C", str(ROOT), "show", f"{ref}:src/satchain/measure/wedge.py"],
                         check=True, capture_output=True, text=True).stdout  # fmt: skip
    path = Path(tempfile.mkdtemp()) / "wedge_before.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("wedge_before", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["wedge_before"] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod.measure_wedge


def _one(fn, img, lw, avg):
    try:
        r = fn(img, line_width_px=lw, average_px=avg)
    except InputError as exc:
        return None, str(exc).split(":")[1].strip()[:40]
    return r, None


def _case(name, fn, img, lw, avg, sigmas, seeds) -> None:
    ref, why = _one(fn, img, lw, avg)
    zero = "refused (" + why + ")" if ref is None else f"noise estimate {ref.noise_std:.2g}"
    print(f"  {name:6s} noise-free: {zero}")
    if ref is None or ref.resolved_line_width_px is None:
        return
    for s in sigmas:
        val, sd, est, refused = [], [], [], 0
        for seed in range(seeds):
            r, _ = _one(fn, img + np.random.default_rng(seed).normal(0, s, img.shape), lw, avg)
            if r is None or r.resolved_line_width_px is None:
                refused += 1
                continue
            val.append(r.resolved_line_width_px)
            sd.append(r.resolved_line_width_px_std)
            est.append(r.noise_std / s)
        if len(val) < 3:
            print(f"  {name:6s} sigma {s:<6g} refused or no crossing in {refused}/{seeds}")
            continue
        val, sd = np.array(val), np.array(sd)
        err, scatter = val - ref.resolved_line_width_px, float(np.std(val, ddof=1))
        print(
            f"  {name:6s} sigma {s:<6g} noise est/true {np.mean(est):5.2f}  error {np.mean(err):+.4f} px  "
            f"scatter {scatter:.4f}  mean sigma {np.mean(sd):.4f}  scatter/sigma {scatter / np.mean(sd):5.2f}  "
            f"coverage(2 sigma) {np.mean(np.abs(err) < 2 * sd):4.0%}" + (f"  ({refused} refused)" if refused else "")
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--before", default="main", help="git ref of the 'before' wedge.py (default: main)")
    ap.add_argument("--average-px", type=int, default=1)
    a = ap.parse_args()
    before = _load_before(a.before)
    for title, width, blur in CASES:
        img = render_wedge(width, rows=48, cols=160, blur=blur, phase=0.21)
        lw = widths_at_columns(width, 160)
        print(f"{title} (stripes {lw[0]:.2f} -> {lw[-1]:.2f} px, average_px {a.average_px})")
        for name, fn in (("before", before), ("after", after)):
            _case(name, fn, img, lw, a.average_px, (0.002, 0.005, 0.015), a.seeds)


if __name__ == "__main__":
    main()
