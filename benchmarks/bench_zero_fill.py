"""Zero fill or dark scene (issue 19): detection and false-alarm rates of the default nodata rule.

`measure edge|find` without ``nodata``/``valid`` take the zeros of an integer image for a fill outside the data
only on evidence (satchain.measure._zero_fill): a clean step from 0 to the level of the pixels further in, on a
border tilted to the pixel grid.  Prints the verdicts (fill / unsure: kept and flagged / data) over

* fills: Baotou-like crops (tests/measure/_render_baotou.py) at AOI tilts 3-45 deg, 20-50 % of the image filled,
  noise-free and noisy, uint16 and uint8 (scaled to 250 DN); and the same crops with an axis-aligned AOI frame;
* real dark targets clipped at 0 (tests/measure/_render_dark.py): an edge, a bar and three bars with ends, at
  0-45 deg, blur 0.3-2 px, dark level 0 / -0.2 / -1 / -5 x the bright level, 4 sub-pixel phases, noise-free and
  with 1 % noise, uint16 and uint8;

then ``measure find`` with defaults on noise-free (quantised) Baotou renders: the combined ACT/ALT MTF at
Nyquist against the exact truth.

    PYTHONPATH=src python benchmarks/bench_zero_fill.py [N_FIND]
"""

import sys
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render_baotou import GAIN_DN, READ_DN, render_baotou, truth_mtf  # noqa: E402
from _render_dark import render_dark_target  # noqa: E402

from satchain.measure._zero_fill import zero_fill_evidence  # noqa: E402
from satchain.measure.find_mtf import measure_found_edges  # noqa: E402

VERDICTS = ("fill", "unsure", "data")


def baotou(angle, fraction, noise, dtype, rng, frame=False):
    """A Baotou-like crop: the exact noise-free render, scaled to ``dtype``, noise, quantised, 0 outside."""
    aoi = 1e3 if frame else None  # a frame: no rotated AOI
    ph = tuple(rng.uniform(-0.5, 0.5, 2))
    img, valid = render_baotou(angle_deg=angle, phase=ph, aoi_px=aoi, fill_fraction=fraction, seed=None, sub=6)
    if frame:  # an axis-aligned AOI: a frame of zeros around the crop
        k = int(round(101 * (1 - np.sqrt(1 - fraction)) / 2))
        valid = np.zeros_like(valid)
        valid[k:-k, k:-k] = True
    scale, top = (1.0, 65535) if dtype == np.uint16 else (250.0 / 9300.0, 255)
    sig = np.sqrt(READ_DN**2 + GAIN_DN * img) * scale if noise else 0.0
    out = np.clip(np.round(img * scale + sig * rng.normal(size=img.shape)), 1, top).astype(dtype)
    return np.where(valid, out, 0).astype(dtype)


def _row(name, c: Counter) -> str:
    n = sum(c.values())
    return f"{name:<48} n={n:5d}  " + "  ".join(f"{v} {100 * c[v] / n:5.1f} %" for v in VERDICTS)


def verdict(img) -> str:
    ev = zero_fill_evidence(img)
    return "data" if ev is None else ev.verdict


def fills() -> None:
    rng = np.random.default_rng(19)
    for frame in (False, True):
        for dtype in (np.uint16, np.uint8):
            for noise in (False, True):
                c = Counter()
                for angle in (3.0, 8.0, 16.8, 25.0, 40.0):
                    for fraction in (0.2, 0.35, 0.5):
                        c[verdict(baotou(angle, fraction, noise, dtype, rng, frame))] += 1
                kind = "axis-aligned AOI frame" if frame else "rotated AOI"
                print(_row(f"fill, {kind}, {np.dtype(dtype).name}, {'noise' if noise else 'no noise'}", c))


def dark_targets() -> None:
    total = Counter()
    for dtype, bright in ((np.uint16, 1000.0), (np.uint8, 200.0)):
        for noise in (0.0, 0.01):
            for kind in ("edge", "bar", "bars"):
                c = Counter()
                for angle in (0.0, 1.0, 2.0, 5.0, 10.0, 20.0, 30.0, 45.0):
                    for blur in (0.3, 0.5, 1.0, 2.0):
                        for dark in (0.0, -0.2, -1.0, -5.0):
                            for off in (0.0, 0.25, 0.5, 0.75):
                                img = render_dark_target(
                                    kind=kind, angle_deg=angle, blur_px=blur, dark=dark * bright, bright=bright,
                                    offset_px=off, bar_px=8.0, noise=noise * bright, seed=int(off * 4),
                                    dtype=dtype, sub=6,
                                )  # fmt: skip
                                c[verdict(img)] += 1
                total += c
                name = f"dark {kind}, {np.dtype(dtype).name}, {'1 % noise' if noise else 'no noise'}"
                print(_row(name, c))
    print(_row("dark targets, all (fill = false alarm)", total))


def find_noise_free(n: int) -> None:
    rng = np.random.default_rng(7)
    err, worst = [], 0.0
    for _ in range(n):
        ang = rng.uniform(10, 20)
        img, _ = render_baotou(angle_deg=ang, phase=tuple(rng.uniform(-0.5, 0.5, 2)), seed=None, sub=8)
        res = measure_found_edges(np.round(img).astype(np.uint16))  # defaults: no nodata, no mask
        t = truth_mtf(0.5, ang)
        e = [res.combined[d].mtf_at_nyquist - t for d in ("ACT", "ALT")]
        err += e
        worst = max(worst, *map(abs, e))
        print(f"  angle {ang:5.2f}: truth {t:.4f}  ACT {e[0]:+.4f}  ALT {e[1]:+.4f}  edges {len(res.edges)}  "
              f"fill {'taken' if any('taken as nodata' in f for f in res.flags) else 'NOT taken'}")  # fmt: skip
    err = np.asarray(err)
    print(f"measure find, defaults, {n} noise-free uint16 renders: combined MTF@Nyq error mean {err.mean():+.4f} "
          f"rms {np.sqrt(np.mean(err**2)):.4f} max {worst:.4f}")  # fmt: skip


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    fills()
    dark_targets()
    find_noise_free(int(args[0]) if args else 10)
