"""Line-of-sight motion from an edge (issue 20, point 4): per-line edge positions and the sinusoids fitted to them.

Edges are rendered exactly and independently of satchain (tests/measure/_render_jitter.py: each pixel the area
integral of a Gaussian-blurred step whose position per line is x0 + y tan(theta) + A sin(2 pi f t_y + phi)).

Part 1, the per-line estimator: rms error against the renderer's truth, in units of the stated 1-sigma, and the
largest phase-locked bias (the error averaged in 10 bins of the sub-pixel phase; the noise of such a bin mean
is printed as ``se``) of
  * ``50 % crossing``: linear interpolation between the two pixels straddling the half level (plateaus from
    each line's outer 4 px),
  * ``centroid``: centroid of the [-1/2, 0, 1/2] derivative over +-4 px around its peak (ISO 12233's per-line
    estimator),
  * ``satchain``: satchain.measure.measure_jitter's positions (the edge's own profile fitted to each line),
on straight edges, 3 seeds x 800 lines, at three blurs and noise levels.

Part 2, the motion: a sweep of tilt x amplitude x frequency x noise (400-800 lines, random phase): the error of
the fitted amplitude and frequency, their errors in units of the stated 1-sigma (|z| < 4 expected), and the
acceptance case of the issue (2 px at 20 Hz over 800 lines of a 3 deg edge at AnkaraSat-3's line time:
2.00 +- 0.05 px); then the false peaks on straight noisy edges (none expected at false_alarm 1e-3) and the time
per measurement.

Run:  python benchmarks/bench_jitter.py [--quick]        (about 1 min; --quick about 15 s)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render_jitter import render_wobbly_edge  # noqa: E402

from satchain.config.system import load_preset  # noqa: E402
from satchain.measure.jitter import measure_jitter  # noqa: E402

DT = 1e-3


def render(n, angle, *, amp=(), freq=(), phase=(), noise=0.0, blur=0.7, dt=DT, seed=0):
    width = int(np.ceil(15.3 + n * np.tan(np.radians(angle)) + max([0.0, *amp]) + 15))
    return render_wobbly_edge(
        n, width, angle_deg=angle, x0=15.3, amp_px=amp, freq_hz=freq, phase_rad=phase, line_time_s=dt,
        blur_px=blur, noise=noise, seed=seed,
    )  # fmt: skip


def crossing_50(img):
    """Per line: linear interpolation of the half level between its outer-4-px plateaus."""
    lo, hi = img[:, :4].mean(axis=1), img[:, -4:].mean(axis=1)
    rel = (img - lo[:, None]) / (hi - lo)[:, None]
    out = np.full(img.shape[0], np.nan)
    for i, r in enumerate(rel):
        k = int(np.argmax(r >= 0.5))
        if k > 0:
            out[i] = k - 1 + (0.5 - r[k - 1]) / (r[k] - r[k - 1])
    return out


def centroid(img, half=4):
    """Per line: centroid of the central-difference derivative over +-half px around its peak."""
    g = np.zeros_like(img)
    g[:, 1:-1] = 0.5 * (img[:, 2:] - img[:, :-2])
    cols = np.arange(img.shape[1], dtype=float)
    peak = np.argmax(g, axis=1)
    win = np.abs(cols[None, :] - peak[:, None]) <= half
    gw = np.where(win, g, 0.0)
    return (gw * cols).sum(axis=1) / gw.sum(axis=1)


def part1(quick: bool):
    print("Part 1: per-line position estimators on straight edges (2.3 deg, 800 lines, step 0.6)")
    print(f"{'blur px':>8} {'noise':>7} {'sigma px':>9} | {'rms/sigma':>28} | {'max phase bias / sigma':>28} | se")
    print(f"{'':>8} {'':>7} {'':>9} | {'50% cross  centroid  satchain':>28} | {'50% cross  centroid  satchain':>28} |")
    for blur in (0.4, 0.7, 1.2):
        for noise in (0.003, 0.01, 0.03):
            errs = {"50": [], "cen": [], "sat": []}
            phs, sigs = [], []
            for seed in range(1 if quick else 3):
                img, truth = render(800, 2.3, noise=noise, blur=blur, seed=seed)
                r = measure_jitter(img, line_time_s=DT)
                errs["50"].append(crossing_50(img) - truth)
                errs["cen"].append(centroid(img) - truth)
                errs["sat"].append(r.edge_position_px - truth)
                phs.append(np.mod(truth, 1.0))
                sigs.append(r.edge_position_sigma_px)
            sig = float(np.nanmedian(np.concatenate(sigs)))
            ph = np.concatenate(phs)
            rms, bias, se = [], [], 0.0
            for key in ("50", "cen", "sat"):
                e = np.concatenate(errs[key])
                e = e - np.nanmean(e)
                rms.append(np.sqrt(np.nanmean(e**2)) / sig)
                b = (ph * 10).astype(int)
                means = np.array([np.nanmean(e[b == i]) for i in range(10)])
                bias.append(np.max(np.abs(means)) / sig)
                if key == "sat":
                    se = float(np.nanstd(e) / np.sqrt(e.size / 10)) / sig
            print(
                f"{blur:8.1f} {noise:7.3f} {sig:9.4f} | {rms[0]:9.2f} {rms[1]:9.2f} {rms[2]:9.2f} | "
                f"{bias[0]:9.2f} {bias[1]:9.2f} {bias[2]:9.2f} | {se:.2f}"
            )


def part2(quick: bool):
    rng = np.random.default_rng(20)
    print("\nPart 2: fitted sinusoids (line time 1 ms, Nyquist 500 Hz; blur 0.7 px, step 0.6)")
    print(
        f"{'tilt':>5} {'A px':>5} {'f Hz':>6} {'noise':>6} | {'A err px':>9} {'z_A':>6} {'f err Hz':>9} {'z_f':>6} | s"
    )
    zs, times = [], []
    tilts = (1.5, 5.0) if quick else (1.5, 3.0, 7.0)
    for tilt in tilts:
        for amp in (0.2, 1.0, 3.0):
            for f in (9.0, 97.0, 333.0):
                for noise in (0.0, 0.02):
                    ph = float(rng.uniform(-np.pi, np.pi))
                    img, _ = render(
                        600, tilt, amp=[amp], freq=[f], phase=[ph], noise=noise, seed=int(rng.integers(1e6))
                    )
                    t0 = time.perf_counter()
                    r = measure_jitter(img, line_time_s=DT, max_peaks=1)
                    times.append(time.perf_counter() - t0)
                    p = r.peaks[0]
                    za = (p.amplitude_px - amp) / max(p.amplitude_sigma_px, 1e-12)
                    zf = (p.frequency_hz - f) / max(p.frequency_sigma_hz, 1e-12)
                    if noise > 0:
                        zs.append((za, zf))
                    print(
                        f"{tilt:5.1f} {amp:5.1f} {f:6.0f} {noise:6.3f} | {p.amplitude_px - amp:9.2e} "
                        f"{za if noise else float('nan'):6.2f} {p.frequency_hz - f:9.2e} "
                        f"{zf if noise else float('nan'):6.2f} | {times[-1]:.2f}"
                    )
    z = np.abs(np.array(zs))
    print(f"noisy cases: rms z_A {np.sqrt(np.mean(z[:, 0] ** 2)):.2f}, rms z_f {np.sqrt(np.mean(z[:, 1] ** 2)):.2f} "
          f"(1 expected), max |z| {z.max():.2f}")  # fmt: skip
    dt = load_preset("ankarasat3").line_time_s
    for noise in (0.0, 0.01, 0.03):
        img, _ = render(800, 3.0, amp=[2.0], freq=[20.0], phase=[0.7], noise=noise, blur=0.6, dt=dt)
        p = measure_jitter(img, line_time_s=dt).peaks[0]
        print(
            f"acceptance (3 deg, 800 lines, line time {dt:.3g} s, 2 px at 20 Hz, noise {noise}): "
            f"A = {p.amplitude_px:.4f} +- {p.amplitude_sigma_px:.4f} px, f = {p.frequency_hz:.3f} +- "
            f"{p.frequency_sigma_hz:.3f} Hz -> {'PASS' if abs(p.amplitude_px - 2.0) <= 0.05 else 'FAIL'} (2.00 +- 0.05)"
        )
    false = 0
    n_straight = 10 if quick else 40
    for k in range(n_straight):
        img, _ = render(500, float(rng.uniform(1, 8)), noise=float(rng.uniform(0.002, 0.03)), seed=1000 + k)
        false += len(measure_jitter(img, line_time_s=DT).peaks)
    print(f"straight noisy edges: {false} false peak(s) in {n_straight} (false_alarm 1e-3 each)")
    print(f"time per measure_jitter (600 lines): median {np.median(times):.2f} s, max {np.max(times):.2f} s")


if __name__ == "__main__":
    q = "--quick" in sys.argv
    part1(q)
    part2(q)
