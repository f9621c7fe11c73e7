"""Slanted-edge accuracy benchmark: satchain.measure.measure_edge vs a plain ISO 12233 (sfrmat3-like) code.

Edges are rendered exactly and independently of satchain.measure (tests/measure/_render.py): the value at a
pixel centre at signed distance d from the edge is
    ESF_n(d) = 1/2 + int_0^fc OTF_n(f) sin(2 pi f d) / (pi f) df
with OTF_n = O'Neill annular diffraction MTF x the 100 %-fill square pixel's signed sinc product, cut along
the edge normal.  100 x 100 px ROIs, angles 3-20 deg, obscuration 0.33, Q = lambda F# / p = 1.07 and 1.8
(Q ~ 2: MTF at Nyquist ~ 0.03).
Noise: none, and Gaussian at SNR 100 (step / sigma) over N_REAL realisations (fixed seed).

Printed per system, angle and noise level: the error of the MTF at Nyquist (0.5 cy/px along the normal),
mean and max |error| and RMS over the realisations, for both methods, and the ratio reference / satchain.

Run:  python benchmarks/bench_edge.py [--quick]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "measure"))
from _render import otf_normal, render_edge  # noqa: E402

from satchain.measure.edge import measure_edge  # noqa: E402

SHAPE = (100, 100)
SNR = 100.0
N_REAL = 20
SYSTEMS = ((1.07, 0.33), (1.8, 0.33))
ANGLES = (3.0, 5.0, 7.5, 10.0, 12.0, 17.0, 20.0, -6.0)


def iso_reference_mtf_at(image: np.ndarray, f_eval: float = 0.5, oversampling: int = 4) -> float:
    """Plain ISO 12233 e-SFR (sfrmat3-like).

    Per-row centroid of the Hamming-windowed [-1/2, 0, 1/2] derivative, linear fit, projection on the normal,
    4x bin averaging, [-1/2, 0, 1/2] derivative with its sinc correction, Hamming window on the LSF, DFT
    normalised at DC.  Assumes a near-vertical edge rising to the right.
    """
    ny, nx = image.shape
    cols = np.arange(nx, dtype=float)
    g = np.zeros_like(image)
    g[:, 1:-1] = 0.5 * (image[:, 2:] - image[:, :-2])
    ham = 0.54 + 0.46 * np.cos(2 * np.pi * (cols - (nx - 1) / 2) / (nx - 1))
    cen = (g * ham * cols).sum(axis=1) / (g * ham).sum(axis=1)
    rows = np.arange(ny, dtype=float)
    # second pass: window centred on each row's first-pass edge (as sfrmat3 does)
    b, a = np.polyfit(rows, cen, 1)
    xe = a + b * rows
    hw = np.clip(np.cos(np.pi * (cols[None, :] - xe[:, None]) / (nx - 1)), 0, None)
    ham2 = 0.54 + 0.46 * (2 * hw**2 - 1)
    cen = (g * ham2 * cols).sum(axis=1) / (g * ham2).sum(axis=1)
    b, a = np.polyfit(rows, cen, 1)
    cos_t = 1.0 / np.hypot(1.0, b)
    d = ((cols[None, :] - (a + b * rows)[:, None]) * cos_t).ravel()
    w = 1.0 / oversampling
    k = np.rint(d / w).astype(int)
    idx = k - k.min()
    cnt = np.bincount(idx)
    esf = np.bincount(idx, weights=image.ravel()) / np.maximum(cnt, 1)
    x = (np.arange(cnt.size) + k.min()) * w
    ok = cnt > 0
    esf[~ok] = np.interp(x[~ok], x[ok], esf[ok])
    lsf = np.gradient(esf)
    c = np.sum(lsf * x) / np.sum(lsf)
    half = max(c - x[0], x[-1] - c)
    win = 0.54 + 0.46 * np.cos(np.pi * np.clip((x - c) / half, -1, 1))
    lsf = lsf * win
    m = np.abs(np.sum(lsf * np.exp(-2j * np.pi * f_eval * x))) / np.sum(lsf)
    return float(m / np.sinc(2 * f_eval * w))


def _stats(err: np.ndarray):
    a = np.abs(err)
    return a.mean(), a.max(), np.sqrt(np.mean(err**2))


def main(quick: bool = False) -> None:
    rng = np.random.default_rng(20240611)
    n_real = 6 if quick else N_REAL
    angles = ANGLES[:3] if quick else ANGLES
    print(f"ROI {SHAPE[1]}x{SHAPE[0]} px, SNR {SNR:g} (step/sigma), {n_real} noise realisations per case")
    print("errors of MTF at Nyquist (0.5 cy/px along the normal); ratio = ISO reference / satchain")
    hdr = f"{'Q':>5} {'angle':>6} {'truth':>7} | {'noise-free err':>15} {'ISO':>9} | "
    hdr += f"{'SNR100 mean|e|':>14} {'max|e|':>7} {'RMS':>7} | "
    hdr += f"{'ISO mean':>8} {'ISO max':>8} {'ISO RMS':>8} | ratio"
    print(hdr)
    all_s, all_r, all_s0, all_r0 = [], [], [], []
    t_meas = 0.0
    n_meas = 0
    for q, eps in SYSTEMS:
        for ang in angles:
            clean = 0.2 + render_edge(SHAPE, ang, q=q, eps=eps)
            truth = float(otf_normal(0.5, ang, q=q, eps=eps))
            e0 = measure_edge(clean).mtf_at_nyquist - truth
            r0 = iso_reference_mtf_at(clean) - truth
            es, er = [], []
            for _ in range(n_real):
                img = clean + rng.normal(0.0, 1.0 / SNR, SHAPE)
                t0 = time.perf_counter()
                es.append(measure_edge(img).mtf_at_nyquist - truth)
                t_meas += time.perf_counter() - t0
                n_meas += 1
                er.append(iso_reference_mtf_at(img) - truth)
            es, er = np.array(es), np.array(er)
            ms, xs, rs = _stats(es)
            mr, xr, rr = _stats(er)
            all_s.append(es), all_r.append(er), all_s0.append(e0), all_r0.append(r0)
            print(
                f"{q:5.2f} {ang:6.1f} {truth:7.4f} | {e0:+15.5f} {r0:+9.5f} | "
                f"{ms:14.4f} {xs:7.4f} {rs:7.4f} | "
                f"{mr:8.4f} {xr:8.4f} {rr:8.4f} | {rr / max(rs, 1e-9):5.2f}"
            )
    n_ang = len(angles)
    s0, r0 = np.abs(all_s0), np.abs(all_r0)
    print(f"\nnoise-free max|err|: satchain {s0.max():.5f}  ISO reference {r0.max():.5f}  (target 0.003)")
    for i, (q, _) in enumerate(SYSTEMS):
        s = np.concatenate(all_s[i * n_ang : (i + 1) * n_ang])
        r = np.concatenate(all_r[i * n_ang : (i + 1) * n_ang])
        rs, rr = np.sqrt(np.mean(s**2)), np.sqrt(np.mean(r**2))
        print(
            f"Q {q:4.2f}, SNR {SNR:g}: RMS err satchain {rs:.4f} (max {np.abs(s).max():.4f})  "
            f"ISO reference {rr:.4f} (max {np.abs(r).max():.4f})  ratio {rr / rs:.2f}  (target 0.015)"
        )
    print(f"satchain measure_edge: {1e3 * t_meas / max(n_meas, 1):.1f} ms per 100x100 edge")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
