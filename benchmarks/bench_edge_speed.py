"""Slanted-edge and ``measure find`` speed (issue 21, point 2): ratios to a lean ISO 12233 e-SFR in the same run.

ROI (rendered here, independently of satchain.measure): a 100 x 100 px edge tilted by 5 deg, the exact ESF of a
Gaussian blur (sigma 0.5 px) integrated over the square pixel, levels 0.2 -> 0.8, signal-dependent noise
(sigma^2 = 1e-5 + 2e-5 x signal: SNR ~ 100 at the edge), fixed seed.  Each ROI of the timing set has its own
noise realisation (8 of them, cycled).

Printed:
* ``measure_edge`` time per ROI (median of ``--repeats`` runs; 5 rounds, the median and the fastest round), the
  lean e-SFR's alike on the same ROIs, and their ratios (target <= 20 x);
* with ``SATCHAIN_OLD_SRC=/path/to/old/src`` set: the same for the old code, imported side by side in this
  process and timed interleaved with the new one, and the largest |difference| of the MTF, its sigma and the
  angle between the two;
* ``measure find`` on a 4000 x 4000 float32 chart (tests/measure/_render_chart.py tiled, fresh noise):
  ``find_edges`` throughput (Mpx/s; target >= 4) and the time per measured edge of ``measure_found_edges`` on
  the 200 longest edges (ms; target <= 20), for the new (and old) code;
* with ``SATCHAIN_OLD_SRC`` and ``--compare N``: every field of the two codes' results (or their refusals) on
  N random ROIs plus fixed cases (:func:`varied_cases`: tilts 1-44 deg and the critical ones, noise from none
  to SNR ~ 5, blur 0.3-2 px, curved, short (12 lines), ALT and falling edges, ``valid`` masks, NaN
  ``nodata``, quantised and clipped integer images, forced degrees, the row axis, ``debias``, 8x
  oversampling, ``roi`` and ``edge_line``): the largest difference of each field (relative for ``cnr`` and
  the numbers inside ``warnings``), any field that differs in kind or shape, or any different outcome.

Run:  PYTHONPATH=src python benchmarks/bench_edge_speed.py [--quick] [--repeats N] [--no-find] [--no-time]
      SATCHAIN_OLD_SRC=/work/main/src PYTHONPATH=src python benchmarks/bench_edge_speed.py   (side by side)
      SATCHAIN_OLD_SRC=/work/main/src PYTHONPATH=src python benchmarks/bench_edge_speed.py --compare 150 \
          --no-time --no-find
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import sys
import time
from pathlib import Path

import numpy as np
from scipy.special import erf

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render_chart import render_chart  # noqa: E402

ANGLE_DEG, BLUR_PX, N_PX = 5.0, 0.5, 100
ROUNDS = 5  # timing rounds (each code timed in turn; the median round and the fastest are printed)


# ------------------------------------------------------------------------------------------------ rendering


def _esf_pixel(d: np.ndarray, s: float) -> np.ndarray:
    """Gaussian-blurred unit step integrated over one pixel width along the normal (closed form)."""

    def prim(z):  # integral of Phi(z / s) dz
        return z * 0.5 * (1 + erf(z / (s * np.sqrt(2)))) + s / np.sqrt(2 * np.pi) * np.exp(-0.5 * (z / s) ** 2)

    return prim(d + 0.5) - prim(d - 0.5)


def render_roi(
    seed: int,
    angle_deg: float = ANGLE_DEG,
    n: int = N_PX,
    *,
    blur: float = BLUR_PX,
    noise: float = 1.0,
    ny: int | None = None,
    radius: float | None = None,
) -> np.ndarray:
    """A noisy slanted edge: exact blurred step, sub-sampled 4 x 4 over each pixel's area.  ``noise`` scales
    the noise's standard deviation, ``ny`` gives a region of ``ny`` rows (``n`` by default), ``radius`` bends
    the edge (x offset ``y^2 / (2 R)`` about the middle row)."""
    t = np.deg2rad(angle_deg)
    ny = n if ny is None else ny
    sub = (np.arange(4) + 0.5) / 4 - 0.5
    yy, xx = np.mgrid[0:ny, 0:n].astype(float)
    acc = np.zeros((ny, n))
    for dy in sub:  # the pixel's extent along the edge (the ESF is already integrated across it)
        yr = yy + dy - ny / 2
        bend = 0.0 if radius is None else yr**2 / (2 * radius)
        d = (xx - (n / 2 + 0.3) - yr * np.tan(t) - bend) * np.cos(t)
        acc += _esf_pixel(d, blur)
    sig = 0.2 + 0.6 * acc / 4
    rng = np.random.default_rng(seed)
    return sig + noise * rng.normal(0.0, 1.0, sig.shape) * np.sqrt(1e-5 + 2e-5 * sig)


# -------------------------------------------------------------------------------------------- lean e-SFR


def lean_esfr(img: np.ndarray, oversampling: int = 4):
    """Minimal ISO 12233 e-SFR: per-row Hamming-windowed derivative centroid, line fit, projection, 4x bins,
    derivative, Hamming window, FFT.  Returns (f cy/px, MTF)."""
    ny, nx = img.shape
    cols = np.arange(nx, dtype=float)
    g = np.zeros_like(img)
    g[:, 1:-1] = 0.5 * (img[:, 2:] - img[:, :-2])
    ham = np.hamming(nx)
    cen = (g * ham * cols).sum(axis=1) / (g * ham).sum(axis=1)
    rows = np.arange(ny, dtype=float)
    coef = np.polyfit(rows, cen, 1)
    ham = 0.54 + 0.46 * np.cos(2 * np.pi * np.clip((cols[None, :] - np.polyval(coef, rows)[:, None]) / nx, -0.5, 0.5))
    cen = (g * ham * cols).sum(axis=1) / (g * ham).sum(axis=1)
    coef = np.polyfit(rows, cen, 1)
    cos_t = 1.0 / np.hypot(1.0, coef[0])
    d = ((cols[None, :] - np.polyval(coef, rows)[:, None]) * cos_t).ravel()
    k = np.floor(d * oversampling).astype(int)
    k -= k.min()
    cnt = np.bincount(k)
    esf = np.bincount(k, weights=img.ravel()) / np.maximum(cnt, 1)
    if np.any(cnt == 0):
        ok = cnt > 0
        esf[~ok] = np.interp(np.nonzero(~ok)[0], np.nonzero(ok)[0], esf[ok])
    lsf = np.diff(esf) * np.hamming(esf.size - 1)
    m = np.abs(np.fft.rfft(lsf))
    f = np.fft.rfftfreq(lsf.size, 1.0 / oversampling)
    return f, m / m[0]


# --------------------------------------------------------------------------------------------- importing


def load_satchain(src: str | None):
    """(measure_edge, find_edges, measure_found_edges) from ``src`` (None: the satchain on sys.path), imported
    as a separate copy of the package (its modules are kept apart in sys.modules)."""
    saved = {k: v for k, v in sys.modules.items() if k == "satchain" or k.startswith("satchain.")}
    for k in saved:
        del sys.modules[k]
    if src:
        sys.path.insert(0, src)
    try:
        edge = importlib.import_module("satchain.measure.edge")
        find = importlib.import_module("satchain.measure.find")
        find_mtf = importlib.import_module("satchain.measure.find_mtf")
        out = (edge.measure_edge, find.find_edges, find_mtf.measure_found_edges)
    finally:
        if src:
            sys.path.remove(src)
        for k in [k for k in sys.modules if k == "satchain" or k.startswith("satchain.")]:
            del sys.modules[k]
        sys.modules.update(saved)
    return out


def median_time(fn, args_list, repeats: int) -> float:
    ts = []
    for i in range(repeats):
        a = args_list[i % len(args_list)]
        t0 = time.perf_counter()
        fn(a)
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


# ----------------------------------------------------------------------------------------------- figures


def edge_figures(impls: dict, repeats: int) -> None:
    rois = [render_roi(s) for s in range(8)]
    for fn in impls.values():  # warm up (imports, caches)
        fn[0](rois[0])
    lean_esfr(rois[0])
    t = {name: [] for name in impls}
    t_lean = []
    # interleaved rounds, each a median of repeats calls in a row (each code in its own tight loop, its data and
    # code in cache: calls interleaved one by one would leave the lean e-SFR's cache cold after each
    # measure_edge and flatter the ratio by a third)
    for _ in range(ROUNDS):
        t_lean.append(median_time(lean_esfr, rois, repeats))
        for name, fn in impls.items():
            t[name].append(median_time(fn[0], rois, repeats))
    lean, lean_min = float(np.median(t_lean)), min(t_lean)
    print(f"slanted edge, {N_PX} x {N_PX} px ROI at {ANGLE_DEG:g} deg, {ROUNDS} rounds of {repeats} runs each:")
    print(f"  lean ISO 12233 e-SFR: {lean * 1e3:.2f} ms (median round), {lean_min * 1e3:.2f} ms (fastest)")
    for name in impls:
        m, m_min = float(np.median(t[name])), min(t[name])
        print(
            f"  measure_edge ({name}): {m * 1e3:.2f} ms = {m / lean:.1f} x the lean e-SFR (median rounds); "
            f"fastest rounds {m_min * 1e3:.2f} ms = {m_min / lean_min:.1f} x (target <= 20 x, about 10 ms)"
        )
    if len(impls) == 2:
        (_, a), (_, b) = impls.items()
        dm = ds = da = 0.0
        for roi in rois:
            ra, rb = a[0](roi), b[0](roi)
            dm = max(dm, float(np.max(np.abs(ra.mtf - rb.mtf))))
            ds = max(ds, float(np.max(np.abs(ra.mtf_sigma - rb.mtf_sigma))))
            da = max(da, abs(ra.angle_deg - rb.angle_deg))
        print(f"  new vs old on the {len(rois)} ROIs: max |dMTF| {dm:.2e}, |dsigma| {ds:.2e}, |dangle| {da:.2e} deg")


def varied_cases(n_random: int, seed: int = 2024):
    """(name, image, keywords) of varied ROIs for the side-by-side comparison: tilts 1-44 deg, noise from none
    to SNR ~ 5, blur 0.3-2 px, curved and short edges, ALT edges, falling edges, masks, NaN nodata, integer
    (quantised, clipped) images and the options that change the path (forced degree, row axis, debias, a given
    edge line, a region given by ``roi``)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n_random):
        ang = float(rng.uniform(1.0, 44.0))
        noise = float(rng.choice([0.0, 0.3, 1.0, 3.0, 10.0]))
        blur = float(rng.choice([0.3, 0.5, 0.8, 1.2, 2.0]))
        nx = int(rng.choice([40, 60, 100, 140]))
        ny = int(rng.choice([12, 20, 40, nx, 160]))
        radius = None if rng.uniform() < 0.7 else float(rng.uniform(150.0, 2000.0))
        img = render_roi(1000 + i, ang, nx, blur=blur, noise=noise, ny=ny, radius=radius)
        kw = {}
        tag = f"a{ang:.1f} n{noise:g} b{blur:g} {ny}x{nx}" + ("" if radius is None else f" R{radius:.0f}")
        r = rng.uniform()
        if r < 0.15:
            img = img.T
            tag += " ALT"
        elif r < 0.25:
            img = 1.0 - img
            tag += " falling"
        r = rng.uniform()
        if r < 0.08:
            valid = np.ones(img.shape, bool)
            valid[: img.shape[0] // 4, : img.shape[1] // 3] = False
            kw["valid"] = valid
            tag += " valid"
        elif r < 0.14:
            img = img.copy()
            img[-3:, -5:] = np.nan
            kw["nodata"] = float("nan")
            tag += " nan"
        elif r < 0.22:
            img = np.round(img * float(rng.choice([60.0, 255.0, 4000.0]))).astype(np.uint16)
            tag += " int"
        elif r < 0.26:
            img = np.clip(img, None, 0.7)
            tag += " clipped"
        r = rng.uniform()
        if r < 0.1:
            kw["fit_degree"] = int(rng.integers(1, 4))
        elif r < 0.18:
            kw["frequency_axis"] = "row"
        elif r < 0.24:
            kw["debias"] = True
        elif r < 0.28:
            kw["f_max_cy_per_px"] = 0.5
        elif r < 0.32:
            kw["oversampling"] = 8
            kw["f_max_cy_per_px"] = 1.5
        if kw:
            tag += " " + " ".join(f"{k}={v}" for k, v in kw.items() if k != "valid")
        out.append((tag, img, kw))
    for ang in (1.0, 2.0, 5.0, 14.036, 18.43, 26.57, 40.0, 45.0):
        out.append((f"critical {ang}", render_roi(7, ang, 100), {}))
    big = render_roi(8, 6.0, 140, ny=120)
    out.append(("roi", big, {"roi": (20, 10, 120, 110)}))
    out.append(("edge_line", big, {"edge_line": (70.3, 60.0, 6.0)}))
    return out


_NUM = re.compile(r"[-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?")


def _diff(a, b) -> float:
    """Largest |difference| of two result fields (inf where they differ in kind, shape or NaN pattern); the
    warnings' texts must be equal but for their numbers, whose largest relative difference is returned."""
    if isinstance(a, tuple | list) and a and isinstance(a[0], str) and len(a) == len(b) and a != b:
        na = [_NUM.findall(x) for x in a]
        nb = [_NUM.findall(x) for x in b]
        if [_NUM.sub("#", x) for x in a] != [_NUM.sub("#", x) for x in b] or list(map(len, na)) != list(map(len, nb)):
            return float("inf")
        x = np.array([float(v) for v in sum(na, [])])
        y = np.array([float(v) for v in sum(nb, [])])
        return float(np.max(np.abs(x - y) / np.maximum(np.abs(y), 1e-300)))
    if isinstance(a, dict) or isinstance(b, dict) or a is None or b is None or isinstance(a, str | bool):
        return 0.0 if a == b else float("inf")
    if isinstance(a, list | tuple) and (not a or isinstance(a[0], str)):
        return 0.0 if list(a) == list(b) else float("inf")
    x = np.asarray(a, dtype=float)
    y = np.asarray(b, dtype=float)
    if x.shape != y.shape or not np.array_equal(np.isnan(x), np.isnan(y)):
        return float("inf")
    ok = np.isfinite(x)
    if not np.array_equal(x[~ok], y[~ok], equal_nan=True):
        return float("inf")
    return float(np.max(np.abs(x[ok] - y[ok]), initial=0.0))


def compare_figures(impls: dict, n_random: int) -> None:
    """Every result field of the new and the old code on :func:`varied_cases` (or the same refusal)."""
    (_, a), (_, b) = impls.items()
    worst: dict[str, tuple[float, str]] = {}
    n_refused = n_same = 0
    cases = varied_cases(n_random)
    for tag, img, kw in cases:
        try:
            ra = a[0](img, **kw).__dict__
        except Exception as exc:  # noqa: BLE001 - compare the refusal itself
            ra = f"{type(exc).__name__}: {exc}"
        try:
            rb = b[0](img, **kw).__dict__
        except Exception as exc:  # noqa: BLE001
            rb = f"{type(exc).__name__}: {exc}"
        if isinstance(ra, str) or isinstance(rb, str):
            n_refused += isinstance(ra, str) and isinstance(rb, str)
            if ra != rb:
                print(f"  DIFFERENT OUTCOME [{tag}]:\n    new: {str(ra)[:200]}\n    old: {str(rb)[:200]}")
                worst["outcome"] = (float("inf"), tag)
            else:
                n_same += 1
            continue
        n_same += 1
        for k in ra:
            d = _diff(ra[k], rb[k])
            if k == "cnr" and np.isfinite(d):  # contrast / noise: huge on noise-free ROIs, compared relatively
                d /= max(abs(rb[k]), 1.0)
            if d > worst.get(k, (-1.0, ""))[0]:
                worst[k] = (d, tag)
    print(f"new vs old on {len(cases)} varied ROIs ({n_refused} refused by both, {n_same} alike):")
    for k, (d, tag) in sorted(worst.items(), key=lambda kv: -kv[1][0]):
        if d > 0:
            how = "relative" if k in ("cnr", "warnings") else ""
            print(f"  max |d {k}| = {d:.2e} {how} [{tag}]")
    print("  every other field identical" if worst else "  all fields identical")


def make_chart(size: int, seed: int = 12345) -> np.ndarray:
    """A ``size`` x ``size`` float32 chart: 5 x 5 squares (as benchmarks/bench_find.py) tiled, fresh noise."""
    rng = np.random.default_rng(seed)
    squares = []
    for i in range(5):
        for j in range(5):
            rot = rng.uniform(3.0, 12.0) * rng.choice([-1, 1])
            squares.append((100 + 200 * j + rng.uniform(0, 1), 100 + 200 * i + rng.uniform(0, 1), 100, rot))
    tile = render_chart((1000, 1000), squares, sx=0.45, sy=0.6, noise=0.004, rng=rng)
    reps = int(np.ceil(size / tile.shape[0]))
    big = np.tile(tile, (reps, reps))[:size, :size]
    return (big + rng.normal(0.0, 0.004, big.shape)).astype(np.float32)


def find_figures(impls: dict, size: int, n_find: int) -> None:
    big = make_chart(size)
    mpx = big.size / 1e6
    print(f"measure find on a {size} x {size} float32 chart ({mpx:.0f} Mpx):")
    for name, (_, find_edges, measure_found) in impls.items():
        ts = []
        for _ in range(n_find):
            t0 = time.perf_counter()
            s = find_edges(big)
            ts.append(time.perf_counter() - t0)
        t_find = float(np.median(ts))
        s200 = find_edges(big, max_edges=200)
        t0 = time.perf_counter()
        res = measure_found(big, search=s200)
        t_meas = time.perf_counter() - t0
        print(
            f"  ({name}) find_edges: {t_find:.2f} s = {mpx / t_find:.1f} Mpx/s (target >= 4), {len(s)} edges; "
            f"measuring the 200 longest: {t_meas:.2f} s = {t_meas / max(len(res.edges), 1) * 1e3:.1f} ms per "
            f"measured edge ({len(res.edges)} measured; target <= 20 ms)"
        )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeats", type=int, default=None)
    ap.add_argument("--no-find", action="store_true")
    ap.add_argument("--compare", type=int, default=0, metavar="N", help="with SATCHAIN_OLD_SRC: N random ROIs")
    ap.add_argument("--no-time", action="store_true", help="skip the slanted-edge timing")
    args = ap.parse_args()
    repeats = args.repeats or (10 if args.quick else 30)
    impls = {"new": load_satchain(None)}
    old = os.environ.get("SATCHAIN_OLD_SRC")
    if old:
        impls["old"] = load_satchain(old)
    if args.compare and old:
        compare_figures(impls, args.compare)
    if not args.no_time:
        edge_figures(impls, repeats)
    if not args.no_find:
        find_figures(impls, 2000 if args.quick else 4000, 1 if args.quick else 3)


if __name__ == "__main__":
    main()
