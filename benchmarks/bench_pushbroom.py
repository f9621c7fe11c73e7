"""Issue 20's acceptance figures for pushbroom motion in time, and the time-domain path's cost against the static
one on the same scene (ankarasat3, noise-free reflectance, 5 deg edges at a 0.07 m scene pixel).

For each case: the budget's MTF at Nyquist (ACT or ALT) against base x the closed form, and the MTF measured on
the simulated edge against the budget; Earth rotation's edge angles against the formulas; then the time taken by
the static and the time-domain simulation of the same scene.

Usage: ``python benchmarks/bench_pushbroom.py [--n 2100] [--speed-n 4200]``
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.special import j0

import satchain
from satchain import load_preset, measure_edge
from satchain.tf.budget import SystemOTF
from satchain.tf.pushbroom import PushbroomTerms

BASE = load_preset("ankarasat3")
PX = 0.07


def edges(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A near-vertical and a near-horizontal 5 deg edge (0.2 / 0.6 reflectance), exact to the pixel centre."""
    y, x = np.mgrid[0:n, 0:n] + 0.5
    t5 = math.tan(math.radians(5.0))
    v = np.where(x - (n / 2 + (y - n / 2) * t5) > 0, 0.6, 0.2)
    h = np.where(y - (n / 2 + (x - n / 2) * t5) > 0, 0.6, 0.2)
    return v, h


def budget_nyquist(system, axis: str) -> float:
    otf, ny = SystemOTF(system), system.nyquist_act_cy_per_mm
    f = (np.array([ny]), np.array([0.0])) if axis == "act" else (np.array([0.0]), np.array([ny]))
    return float(np.abs(otf(*f))[0])


def measured_nyquist(system, image: np.ndarray, axis: str) -> float:
    img = satchain.simulate_image(image, system, pixel_m=PX).image
    m = img.shape[0] // 2
    roi = img[m - 100 : m + 100, m - 30 : m + 30] if axis == "act" else img[m - 30 : m + 30, m - 100 : m + 100]
    return float(measure_edge(roi).mtf_at_nyquist)


def wobble(tau: float) -> None:
    """ACT oscillation 2 px at 20 Hz over 800 lines: a sinusoid fitted to the per-line positions of a 3 deg edge
    (`measure jitter`) and the edge's MTF against the static image's."""
    from satchain.measure.jitter import measure_jitter

    s = BASE.replace({"motion.oscillation": [{"axis": "act", "amplitude_px": 2.0, "frequency_hz": 20.0,
                                              "phase_deg": 10.0}]})  # fmt: skip
    ny, nx = 800 * 7 + 14, 420
    y, x = np.mgrid[0:ny, 0:nx] + 0.5
    img = np.where(x - (nx / 2 + (y - ny / 2) * math.tan(math.radians(3.0))) > 0, 0.6, 0.2)
    moving = satchain.simulate_image(img, s, pixel_m=PX).image
    static = satchain.simulate_image(img, BASE, pixel_m=PX).image
    j = measure_jitter(moving, line_time_s=tau).to_dict()
    p = min(j["peaks"], key=lambda q: abs(q["frequency_hz"] - 20.0))
    m0 = measure_edge(static[300:500, 20:40]).mtf_at_nyquist
    m1 = measure_edge(moving[300:500, 20:40]).mtf_at_nyquist
    print(f"ACT oscillation 2 px at 20 Hz over {moving.shape[0]} lines, 3 deg edge: fitted {p['amplitude_px']:.4f} "
          f"+- {p['amplitude_sigma_px']:.4f} px at {p['frequency_hz']:.3f} Hz (goal 2.00 +- 0.05); MTF@Nyquist "
          f"{m1:.4f} vs static {m0:.4f} (|d| {abs(m1 - m0):.4f}, goal <= 0.02)")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=2100)
    ap.add_argument("--speed-n", type=int, default=4200)
    a = ap.parse_args()
    v, h = edges(a.n)
    tau, n_st = BASE.line_time_s, BASE.detector.tdi_stages
    cases = [
        ("ACT oscillation 0.5 px, 5 cycles/window", "act",
         {"motion.oscillation": [{"axis": "act", "amplitude_px": 0.5, "frequency_hz": 5 / (n_st * tau)}]},
         lambda nu: abs(float(j0(2 * math.pi * 0.5 * nu))), 0.003),
        ("line_rate_error 0.05 over 16 stages", "alt", {"motion.line_rate_error": 0.05},
         lambda nu: abs(math.sin(math.pi * 16 * 0.05 * nu) / (math.pi * 16 * 0.05 * nu)), 0.003),
        ("ACT PSD 5-50 kHz, sigma 0.40 px", "act",
         {"motion.jitter_psd": {"axis": "act", "frequency_hz": [5e3, 5e4], "psd_px2_per_hz": [3.6e-6, 3.6e-6]}},
         lambda nu: math.exp(-2 * math.pi**2 * 0.162 * nu**2), 0.006),
    ]  # fmt: skip
    print(f"{'case':42s} {'budget':>8s} {'base x form':>11s} {'|d|':>7s} {'tol':>6s}  {'measured':>8s} {'|d|':>7s}")
    for name, axis, keys, form, tol in cases:
        s = BASE.replace(keys)
        b, b0 = budget_nyquist(s, axis), budget_nyquist(BASE, axis)
        m = measured_nyquist(s, v if axis == "act" else h, axis)
        c = b0 * form(0.5)
        print(f"{name:42s} {b:8.4f} {c:11.4f} {abs(b - c):7.4f} {tol:6.3f}  {m:8.4f} {abs(m - b):7.4f}")
    s = BASE.replace({"orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True})
    g = PushbroomTerms(s).geometry()
    sig, e, t5 = g["shear_act_px_per_line"], g["alt_scale"] - 1, math.tan(math.radians(5))
    mv = satchain.simulate_image(v, s, pixel_m=PX).image
    mh = satchain.simulate_image(h, s, pixel_m=PX).image
    k = mv.shape[0] // 2
    av = measure_edge(mv[k - 100 : k + 100, k - 30 : k + 30]).angle_deg
    ah = 90 - measure_edge(mh[k - 30 : k + 30, k - 100 : k + 100]).angle_deg
    pv, ph = math.degrees(math.atan((1 + e) * t5 - sig)), math.degrees(math.atan(t5 / (1 + e - sig * t5)))
    print(f"Earth rotation (lat 0, i 97.6, descending): vertical edge {av:.4f} deg (predicted {pv:.4f}, "
          f"|d| {abs(av - pv):.4f}); horizontal edge {ah:.4f} deg (predicted {ph:.4f}, "
          f"|d| {abs(ah - ph):.4f})")  # fmt: skip
    yaw_s = s.replace({"orbit.yaw_steering": True})
    yv = satchain.simulate_image(v, yaw_s, pixel_m=PX).image
    yh = satchain.simulate_image(h, yaw_s, pixel_m=PX).image
    lin = PushbroomTerms(yaw_s).image_affine(yv.shape)
    dv, dh = (lin.a * t5 + lin.b, lin.d * t5 + lin.e), (lin.a + lin.b * t5, lin.d + lin.e * t5)
    pv, ph = math.degrees(math.atan2(dv[0], dv[1])), math.degrees(math.atan2(dh[1], dh[0]))
    av = measure_edge(yv[k - 100 : k + 100, k - 30 : k + 30]).angle_deg
    ah = 90 - measure_edge(yh[k - 30 : k + 30, k - 100 : k + 100]).angle_deg
    print(f"yaw steering (rotation {PushbroomTerms(yaw_s).geometry()['rotation_deg']:.4f} deg): vertical edge "
          f"{av:.4f} deg (predicted {pv:.4f}, |d| {abs(av - pv):.4f}); horizontal edge {ah:.4f} deg (predicted "
          f"{ph:.4f}, |d| {abs(ah - ph):.4f})")  # fmt: skip
    wobble(tau)
    big = edges(a.speed_n)[0]
    for name, keys in [("ACT oscillation (one axis)", cases[0][2]), ("Earth rotation (both axes)", {
            "orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True}),
            ("yaw steering (frame rotated)", {"orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6,
             "orbit.earth_rotation": True, "orbit.yaw_steering": True})]:  # fmt: skip
        t = time.perf_counter()
        satchain.simulate_image(big, BASE, pixel_m=PX)
        t_static = time.perf_counter() - t
        t = time.perf_counter()
        satchain.simulate_image(big, BASE.replace(keys), pixel_m=PX)
        t_time = time.perf_counter() - t
        print(f"speed, {a.speed_n}^2 input, {name}: static {t_static:.2f} s, in time {t_time:.2f} s "
              f"(ratio {t_time / t_static:.2f}; goal <= 3)")  # fmt: skip


if __name__ == "__main__":
    main()
