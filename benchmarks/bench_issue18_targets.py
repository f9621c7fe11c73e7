"""Issue 18 audit cases for the Siemens star and the bar targets, on exact renders (tests/measure renderers,
independent of satchain.measure).  Prints, for the satchain on ``PYTHONPATH``:

1. star (32 cycles, Gaussian blur 0.5 px, 4 x 4 sub-pixel integration) given a centre 0.5-9 px off in four
   directions: refused (the message) or the centre error and the max |MTF@Nyquist error| over the four
   directions (input modulation given);
2. a bar target (12, 6, 4, 3, 2.5, 2 px; Gaussian 0.5 px) at grid phases 0, 0.25, 0.5, 0.75: groups kept,
   groups refused, max |CTF - Coltman| over the kept groups of >= 2.5 px;
3. an obscured-pupil target (Q = 1, obscuration 0.33; 16 ... 3 px) with default levels across 8 grid phases:
   refused (why) or the max |CTF - Coltman| (>= 2.5 px).

Run:  PYTHONPATH=src python benchmarks/bench_issue18_targets.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render import bar_coltman, render_bar_group  # noqa: E402
from test_bars import _coltman, _group  # noqa: E402
from test_star import DIRS, MTFS, _render_star, _truth  # noqa: E402

from satchain.errors import SatchainError  # noqa: E402
from satchain.measure.bars import measure_bars  # noqa: E402
from satchain.measure.star import measure_star  # noqa: E402


def _target(periods, phase, render):
    blocks, rois, x0 = [], [], 0
    for p in periods:
        img, roi = render(p, phase)
        blocks.append(img)
        rois.append((roi[0] + x0, 0, roi[2] + x0, img.shape[0]))
        x0 += img.shape[1]
    return np.hstack(blocks), rois


def star() -> None:
    n, mtf, centre = 32, MTFS["gaussian"], (60.3, 59.6)
    img = _render_star(n, centre, mtf)
    truth = {k: float(_truth(np.array([0.5]), mtf, a)[0]) for k, a in DIRS.items()}
    print("1. star, given centre off by d px at angle a:")
    for d in (0.5, 3.0, 5.0, 9.0):
        for a in (0, 40, 135, 250):
            g = (centre[0] + d * np.cos(np.deg2rad(a)), centre[1] + d * np.sin(np.deg2rad(a)))
            try:
                r = measure_star(img, cycles=n, center=g, input_modulation=0.4)
            except SatchainError as exc:
                print(f"  d {d:3.1f} a {a:3d}: refused: {str(exc)[:110]}")
                continue
            err = max(abs(r.mtf_at_nyquist[k] - truth[k]) for k in DIRS)
            c = np.hypot(r.center_xy_px[0] - centre[0], r.center_xy_px[1] - centre[1])
            print(f"  d {d:3.1f} a {a:3d}: centre error {c:.4f} px, max |MTF@Nyquist error| {err:.4f}")


def bars_phase() -> None:
    periods, s = (12.0, 6.0, 4.0, 3.0, 2.5, 2.0), 0.5
    truth = np.array([_coltman(1 / p, s) for p in periods])
    print("2. bar target 12..2 px, Gaussian 0.5 px, levels given:")
    for phase in (0.0, 0.25, 0.5, 0.75):
        img, rois = _target(periods, phase, lambda p, ph: _group(p, ph, 3, s))
        try:
            r = measure_bars(img, periods_px=periods, group_rois=rois, levels=(40.0, 160.0))
        except SatchainError as exc:
            print(f"  phase {phase:4.2f}: refused whole: {str(exc)[:100]}")
            continue
        kept = [p for p, c in zip(periods, r.ctf, strict=True) if np.isfinite(c)]
        ok = np.isfinite(r.ctf) & (np.asarray(periods) >= 2.5)
        refused = [periods[i] for i, _ in getattr(r, "refused", ())]
        print(
            f"  phase {phase:4.2f}: kept {kept}, refused {refused}, max |CTF - Coltman| (>= 2.5 px) "
            f"{np.max(np.abs(r.ctf - truth)[ok]):.4f}"
        )


def diffraction_sweep() -> None:
    periods, q, eps = (16.0, 12.0, 8.0, 6.0, 5.0, 4.0, 3.0), 1.0, 0.33
    truth = np.array([bar_coltman(1 / p, q=q, eps=eps, blur_sigma_px=0.0) for p in periods])
    print("3. obscured pupil Q = 1, default levels, across the grid phase:")
    for phase in np.arange(8) / 8:
        img, rois = _target(
            periods, phase, lambda p, ph: render_bar_group(p, ph, 3, q=q, eps=eps, blur_sigma_px=0.0, rows=4)
        )
        try:
            r = measure_bars(img, periods_px=periods, group_rois=rois)
        except SatchainError as exc:
            print(f"  phase {phase:5.3f}: refused: {str(exc)[:150]}")
            continue
        print(f"  phase {phase:5.3f}: max |CTF - Coltman| {np.max(np.abs(r.ctf - truth)):.4f} ({r.levels_from})")


if __name__ == "__main__":
    star()
    bars_phase()
    diffraction_sweep()
