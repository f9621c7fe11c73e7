"""Staggered arrays imaged through the engine (issue 32 point 5, point 7's staggered line): two simulations of a
layout, array B's ground window half a GSD from A's along and across track, combined on the half-GSD grid; the
MTF measured on slanted edges at the combined grid's Nyquist and at one array's against the prediction (system
MTF x the combination's transfer function), and bars finer than one array's Nyquist resolved in the combined image
with Coltman's CTF of that MTF while one array cannot measure them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from affine import Affine

import satchain
from satchain import load_preset
from satchain.engine.simulate import simulate
from satchain.engine.staggered import simulate_staggered
from satchain.errors import ConfigError, InputError
from satchain.measure.auto import measure_auto
from satchain.measure.bars import measure_bars
from satchain.measure.edge import measure_edge
from satchain.scene import BarTarget, Scene, SlantedEdge
from satchain.tf.budget import SystemOTF
from satchain.tf.ctf import coltman_ctf
from satchain.tf.staggered import combination_otf

#: the reference camera (ankarasat3: 5.88 um, 100 % fill, Q = 1.07) as two staggered arrays
REF = load_preset("ankarasat3").replace({"detector.layout": "staggered"})
#: an undersampled pair (Q = 0.54): 11.76 um pixels (GSD 0.98 m, combined 0.49 m), a 50 % photosite, a half-line
#: exposure (smear 0.5 px): its MTF at the combined Nyquist 1/p is not 0 in either direction
COARSE = load_preset("ankarasat3").replace(
    {"detector.layout": "staggered", "detector.pitch_m": 11.76e-6, "detector.fill_factor": 0.5, "motion.smear_px": 0.5}
)
TILT_DEG = 5.0


def _edge_scene(system, measures: str) -> Scene:
    g = system.gsd_m
    edge = SlantedEdge("e", center_m=(30 * g, 30 * g), size_m=48 * g, angle_deg=TILT_DEG, measures=measures)
    return Scene(60 * g, 60 * g, (edge,), background=0.2)


def _predicted(system, f_cy_per_mm: float, measures: str) -> float:
    """System MTF x combination transfer along the edge's normal (TILT_DEG from the x axis for an ACT edge)."""
    t = math.radians(TILT_DEG)
    along, across = f_cy_per_mm * math.cos(t), f_cy_per_mm * math.sin(t)
    fx, fy = (along, across) if measures == "act" else (across, along)
    p = system.detector.pitch_x_m
    return abs(complex(np.asarray(SystemOTF(system)(fx, fy)))) * float(combination_otf(fx, fy, pitch_m=p))


def test_a_single_array_system_is_refused():
    with pytest.raises(ConfigError, match=r"detector.layout = 'single'.*layout = 'staggered'"):
        simulate_staggered(_edge_scene(REF, "act"), load_preset("ankarasat3"), window=(0, 0, 8, 8))


def test_each_array_is_the_layout_through_the_engine_half_a_gsd_apart():
    """A is the engine's image of the layout rendered over its window; B of the layout rendered over the window
    moved by half a GSD (7 scene pixels of 0.035 m) along and across track; the combination holds both; the
    transform puts A's and B's pixel centres where their windows are."""
    scene, win, ctx = _edge_scene(REF, "act"), (20, 24, 24, 20), 32  # the edge crosses the window
    r = simulate_staggered(scene, REF, window=win, context_px=ctx)
    k, px = 14, 0.035  # scene pixels per GSD (0.49 m)
    for img, shift in ((r.a, 0), (r.b, k // 2)):
        ground = scene.render(((win[0] - ctx) * k + shift, (win[1] - ctx) * k + shift, (win[2] + 2 * ctx) * k,
                               (win[3] + 2 * ctx) * k), pixel_m=px)  # fmt: skip
        ref = simulate(np.asarray(ground, float), REF, pixel_m=px)[ctx : ctx + win[2], ctx : ctx + win[3]]
        assert np.abs(img - ref).max() < 1e-4  # (beyond the context: the border rule, as here)
    assert np.array_equal(r.combined[0::2, 0::2], r.a) and np.array_equal(r.combined[1::2, 1::2], r.b)
    g = REF.gsd_m
    assert r.transform.almost_equals(Affine(g / 2, 0, 24 * g + g / 4, 0, g / 2, 20 * g + g / 4))
    assert r.transform @ (0.5, 0.5) == pytest.approx(((24 + 0.5) * g, (20 + 0.5) * g))  # A's pixel (0, 0)
    assert r.transform @ (1.5, 1.5) == pytest.approx(((24 + 1) * g, (20 + 1) * g))  # B's pixel (0, 0)
    assert r.combination == "quincunx_bilinear" and r.combined_gsd_m == pytest.approx((g / 2, g / 2))


def test_a_half_gsd_off_the_scene_pixels_is_the_detector_grids_phase():
    """At 0.04 m scene pixels half a GSD is 6.125 of them: the remainder moves the detector grid (the engine's
    exact footprint phase) and the images equal those at 0.035 m (7 whole pixels) within the rasters' own error."""
    scene, win = _edge_scene(REF, "act"), (20, 24, 24, 20)
    whole, split = (simulate_staggered(scene, REF, window=win, pixel_m=px) for px in (0.035, 0.04))
    assert np.abs(whole.combined - split.combined).max() < 1e-3  # a 0.005 m error would be 8e-3 at the edge


def test_the_edge_located_in_each_array_is_one_ground_line():
    """Measured in A and in B alone, each through its own half-GSD-shifted window, the edge falls on the same
    ground line (the layout's), and so does the combined image's through its transform."""
    scene, g = _edge_scene(REF, "act"), REF.gsd_m
    r = simulate_staggered(scene, REF, window=(4, 4, 53, 53))
    t = math.radians(TILT_DEG)
    normal, c = np.array([math.cos(t), -math.sin(t)]), np.array([30 * g, 30 * g])
    maps = {"a": Affine(g, 0, 4 * g, 0, g, 4 * g), "b": Affine(g, 0, 4.5 * g, 0, g, 4.5 * g), "combined": r.transform}
    for name, m in maps.items():
        img = getattr(r, name)
        cut = 6 if name != "combined" else 12
        e = measure_edge(img[cut:-cut, cut:-cut])
        x, y = e.edge_point_xy
        ground = np.array(m @ (x + cut + 0.5, y + cut + 0.5))  # pixel centres at index + 1/2
        assert abs(float((ground - c) @ normal)) < 0.01 * g, name


def test_noise_is_each_arrays_own():
    scene = Scene(20.0, 20.0, background=0.3)
    kw = {"window": (2, 2, 32, 32), "units": "electrons"}
    clean = simulate_staggered(scene, REF, **kw)
    one, again = (simulate_staggered(scene, REF, noise=True, seed=5, **kw) for _ in range(2))
    other = simulate_staggered(scene, REF, noise=True, seed=6, **kw)
    assert np.array_equal(one.combined, again.combined) and not np.array_equal(one.a, other.a)
    na, nb = (one.a - clean.a).ravel(), (one.b - clean.b).ravel()
    assert na.std() > 10 and nb.std() == pytest.approx(na.std(), rel=0.2)  # shot + read noise, electrons
    assert abs(np.corrcoef(na, nb)[0, 1]) < 4 / math.sqrt(na.size)  # independent draws


@pytest.mark.parametrize("system", [REF, COARSE], ids=["reference", "coarse_half_fill"])
@pytest.mark.parametrize("measures", ["act", "alt"])
def test_edge_mtf_at_both_nyquists_matches_the_prediction(system, measures):
    r = simulate_staggered(_edge_scene(system, measures), system, window=(4, 4, 53, 53))
    e = measure_edge(r.combined[12:-12, 12:-12], f_max_cy_per_px=1.0)
    p_mm = system.detector.pitch_x_m * 1e3
    budget = satchain.budget(system).to_dict()["staggered"]
    for key, f_px in (("mtf_at_combined_nyquist", 0.5), ("mtf_at_single_nyquist", 0.25)):  # cy per combined px
        measured = float(np.interp(f_px, e.f_cy_per_px, e.mtf))
        assert measured == pytest.approx(_predicted(system, 2 * f_px / p_mm, measures), abs=0.02), key
        assert measured == pytest.approx(budget[key][measures], abs=0.02), key  # the budget's, on the axis
    if system is COARSE:
        assert budget["mtf_at_combined_nyquist"][measures] > 0.03
    else:  # the reference camera's diffraction cutoff 1/(lambda N) lies below 1/p: 0 there at any fill factor
        assert 1 / (REF.optics.wavelengths_m[0] * REF.f_number * 1e3) < 1 / p_mm
        half = REF.replace({"detector.fill_factor": 0.5})
        assert satchain.budget(half).to_dict()["staggered"]["mtf_at_combined_nyquist"][measures] == 0.0


def _bar_run(system, orientation: str, multiples):
    """A 3-bar target (bars 15 widths long: rows enough to average the quincunx's alias checkerboard) with
    periods ``multiples`` x the GSD, its combined image measured as `satchain run` measures bars."""
    g = system.gsd_m
    target = BarTarget("bars", origin_m=(6 * g, 6 * g), periods_m=tuple(m * g for m in multiples),
                       orientation=orientation, length_factor=15.0)  # fmt: skip
    scene = Scene(60 * g, 40 * g, (target,), background=0.2)
    r = simulate_staggered(scene, system, window=(0, 0, 40, 60))
    origin = (r.transform.c, r.transform.f)  # the combined image's top-left corner on the ground
    combined = measure_auto(r.combined, scene.truth(), pixel_m=g / 2, origin_m=origin).to_dict()
    single = measure_auto(r.a, scene.truth(), pixel_m=g, origin_m=(0.0, 0.0)).to_dict()
    return r, combined, single


@pytest.mark.parametrize(
    ("system", "orientation", "multiples"),
    [(COARSE, "act", (1.3, 1.55, 1.8)), (COARSE, "alt", (1.3, 1.55, 1.8)), (REF, "act", (1.6, 1.75, 1.9))],
    ids=["coarse-act", "coarse-alt", "reference-act"],
)
def test_bars_finer_than_one_arrays_nyquist_are_resolved_as_predicted(system, orientation, multiples):
    """Periods between p and 2p (frequencies between one array's Nyquist and the combined one): the combined
    image's CTF is Coltman's CTF of the system MTF x the combination's transfer function (the rows' mean of the
    quincunx-filled image is the samples of the image through the 3-tap [1/8, 3/4, 1/8] filter); one array
    cannot measure them (below 2 px per period) and its samples are those of bars at the alias frequency."""
    r, combined, single = _bar_run(system, orientation, multiples)
    (bars,) = combined["bar_targets"]
    assert bars["periods_px"] == pytest.approx([2 * m for m in multiples])  # 2.6 to 3.8 combined px
    p_mm = system.detector.pitch_x_m * 1e3
    otf = SystemOTF(system)

    def mtf(f_cy_per_px):  # on the combined grid: 1 cy/px = 2/p
        f = np.asarray(f_cy_per_px, float) * 2 / p_mm
        fx, fy = (f, 0 * f) if orientation == "act" else (0 * f, f)
        return np.abs(otf(fx, fy)) * combination_otf(fx, fy, pitch_m=p_mm / 1e3)

    f = np.asarray(bars["f_cy_per_px"], float)
    predicted = np.asarray(coltman_ctf(f, mtf), float)
    assert np.all(f > 0.25) and np.all(predicted > 0.09)  # above one array's Nyquist, and resolved
    assert np.asarray(bars["ctf"], float) == pytest.approx(predicted, abs=0.02)
    assert single["bar_targets"] == []
    (skip,) = [s for s in single["skipped"] if s["id"] == "bars"]  # every group below 2 px per period
    assert skip["reason"].startswith(f"no bar group is measurable at {system.gsd_m:g} m pixels")
    roi = tuple(v // 2 for v in bars["groups"][-1]["roi_px"])  # the widest group, in A's pixels
    with pytest.raises(InputError, match=r"every period must be >= 2 px \(Nyquist\)"):
        measure_bars(r.a, periods_px=[multiples[-1]], group_rois=[roi], direction=orientation.upper())
