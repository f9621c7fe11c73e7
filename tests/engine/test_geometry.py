"""Geometry contract of detector sampling, edge positions and the direction of smear.

To see the sampling geometry alone the optics must be transparent: a system whose diffraction cutoff
lies ~7e5 times above the input Nyquist frequency (100 m aperture, 10 nm wavelength, 1 km range, same
GSD), no smear, no jitter. Its OTF differs from 1 by < 1e-5 on the input band, so each output pixel is
the overlap-weighted mean of the input pixels under its footprint.
"""

from __future__ import annotations

import numpy as np
import pytest
from _reference import cy_per_input_px_to_cy_per_mm, overlap_matrix

from satchain import load_preset
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import ArraySource
from satchain.tf.budget import SystemOTF

BASE = load_preset("ankarasat3")


def _transparent(system):
    alt_m = 1000.0
    return system.replace(
        {
            "orbit.altitude_m": alt_m,
            "optics.aperture_diameter_m": 100.0,
            "optics.focal_length_m": system.detector.pitch_y_m * alt_m / system.gsd_alt_m,  # same GSD
            "optics.wavelength_m": 1e-8,
            "optics.obscuration_ratio": 0.0,
            "motion.smear_px": 0.0,
        }
    )


IDEAL = _transparent(BASE)


def _run(system, pixel_m, image, **params):
    sim = Simulator(system, input_pixel_m=pixel_m, input_shape=image.shape, params=SimParams(**params))
    return sim, sim.run(ArraySource(image, pixel_m=pixel_m))


def test_transparent_system_is_transparent():
    assert abs(IDEAL.gsd_alt_m - BASE.gsd_alt_m) < 1e-12
    nyquist_cy_per_mm = cy_per_input_px_to_cy_per_mm(IDEAL, 0.04) * 0.5  # the coarsest input used here
    otf = SystemOTF(IDEAL)(
        np.array([0.0, nyquist_cy_per_mm]),
        np.array([nyquist_cy_per_mm, nyquist_cy_per_mm]),
        exclude=("detector",),
    )
    assert np.all(np.abs(otf - 1.0) < 1e-5)


@pytest.mark.parametrize("border", ["periodic", "symmetric"])
def test_integer_ratio_output_is_block_mean(border):
    """k = 14: output (i, j) is the mean of input [14 i, 14 (i+1)) x [14 j, 14 (j+1))."""
    img = np.random.default_rng(0).uniform(0.0, 1.0, (280, 420))
    sim, out = _run(IDEAL, 0.035, img, border=border, far_margin_px=4)
    assert sim.k_int == (14, 14) and out.shape == (20, 30)
    block_mean = img.reshape(20, 14, 30, 14).mean(axis=(1, 3))
    np.testing.assert_allclose(out, block_mean, rtol=0, atol=1e-6)


@pytest.mark.parametrize(("row", "col"), [(0, 0), (13, 13), (14, 27), (151, 98), (279, 419)])
def test_single_bright_pixel_lands_in_its_detector_pixel(row, col):
    img = np.zeros((280, 420))
    img[row, col] = 1.0
    _, out = _run(IDEAL, 0.035, img, border="periodic")
    expected = np.zeros((20, 30))
    expected[row // 14, col // 14] = 1.0 / 14**2
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-7)


SYSTEMS = {
    "k12.25": (IDEAL, 0.04, (245, 294), (0.0, 0.0)),
    "k12.25_phase": (IDEAL, 0.04, (245, 294), (3.3, 5.7)),
    "k14_fill0.5": (_transparent(BASE.replace({"detector.fill_factor": 0.5})), 0.035, (280, 420), (0.0, 0.0)),
    "k14_fill0.5_phase": (
        _transparent(BASE.replace({"detector.fill_factor": 0.5})),
        0.035,
        (280, 420),
        (2.5, 0.4),
    ),
    "rect_k16.8x14": (
        _transparent(BASE.replace({"detector.pitch_y_m": 7.056e-6, "detector.active_width_y_m": 7.056e-6})),
        0.035,
        (336, 280),
        (0.0, 1.0),
    ),
}


@pytest.mark.parametrize("case", list(SYSTEMS))
def test_fractional_overlaps(case):
    """Any ratio, fill factor and phase: output pixel = overlap-weighted mean of the input pixels under
    its active footprint (centred at phase + (i + 1/2) k, width k * active / pitch)."""
    system, pixel_m, shape, phase = SYSTEMS[case]
    img = np.random.default_rng(1).uniform(0.0, 1.0, shape)
    sim, out = _run(system, pixel_m, img, border="periodic", phase_px=phase)
    det = system.detector
    wy = overlap_matrix(
        shape[0],
        k=sim.k[0],
        fill=det.active_width_y_m / det.pitch_y_m,
        phase_px=phase[0],
        n_output=out.shape[0],
    )
    wx = overlap_matrix(
        shape[1],
        k=sim.k[1],
        fill=det.active_width_x_m / det.pitch_x_m,
        phase_px=phase[1],
        n_output=out.shape[1],
    )
    np.testing.assert_allclose(out, wy @ img @ wx.T, rtol=0, atol=1e-6)


def test_fill_factor_shrinks_the_aperture_about_the_pixel_centre():
    """Fill 0.25 (area): active width k / 2 = 7 px centred in each 14-px cell, i.e. input [3.5, 10.5)."""
    system = _transparent(BASE.replace({"detector.fill_factor": 0.25}))
    for col, expected in [(3, 0.5 / 7), (4, 1 / 7), (10, 0.5 / 7), (11, 0.0), (2, 0.0)]:
        img = np.zeros((280, 280))
        img[:, col] = 1.0  # a bright column
        _, out = _run(system, 0.035, img, border="periodic")
        np.testing.assert_allclose(out[:, 0], expected, rtol=0, atol=1e-7)


def _edge(shape, position_px, axis, lo=0.2, hi=0.8):
    img = np.full(shape, lo)
    sl = [slice(None), slice(None)]
    sl[axis] = slice(position_px, None)
    img[tuple(sl)] = hi
    return img


@pytest.mark.parametrize("axis", [0, 1], ids=["ALT", "ACT"])
def test_edge_midpoint_lands_where_the_geometry_says(axis):
    """Real optics (symmetric PSF, smear centred on mid-exposure). A 0.2 -> 0.8 step exactly at an
    output pixel's centre makes that pixel 0.5; a step on the boundary between output pixels i-1, i
    makes them sum to 1. Moving the step by one input pixel changes these by ~1e-2."""
    shape = (1400, 560) if axis == 0 else (560, 1400)
    for position, check in [(50 * 14 + 7, "centre"), (50 * 14, "boundary"), (50 * 14 + 8, "shifted")]:
        _, out = _run(BASE, 0.035, _edge(shape, position, axis))
        prof = out.mean(axis=1 - axis)
        assert np.ptp(out, axis=1 - axis).max() < 1e-5  # a straight edge: every line alike
        if check == "centre":
            assert abs(prof[50] - 0.5) < 1e-4
        elif check == "boundary":
            assert abs(prof[49] + prof[50] - 1.0) < 1e-4
        else:
            assert abs(prof[50] - 0.5) > 1e-2


def test_edge_midpoint_non_integer_ratio():
    """k = 12.25 with phase 3.375: output pixel 50 is centred at 3.375 + 50.5 * 12.25 = 622.0."""
    _, out = _run(BASE, 0.04, _edge((490, 1225), 622, axis=1), phase_px=(0.0, 3.375))
    assert abs(out[:, 50].mean() - 0.5) < 1e-4


def _no_smear_and_smear(smear_px):
    return BASE.replace({"motion.smear_px": 0.0}), BASE.replace({"motion.smear_px": smear_px})


def test_smear_acts_along_track_only():
    """motion.smear_px smears rows (axis 0, ALT): an edge varying along x (ACT) is unchanged, an edge
    varying along y is blurred, symmetrically about mid-exposure (the midpoint stays put)."""
    still, moving = _no_smear_and_smear(3.0)
    act_edge = _edge((560, 1400), 50 * 14 + 7, axis=1)
    _, a0 = _run(still, 0.035, act_edge)
    _, a1 = _run(moving, 0.035, act_edge)
    np.testing.assert_allclose(a1, a0, rtol=0, atol=1e-6)

    alt_edge = _edge((1400, 560), 50 * 14 + 7, axis=0)
    _, b0 = _run(still, 0.035, alt_edge)
    _, b1 = _run(moving, 0.035, alt_edge)
    p0, p1 = b0.mean(axis=1), b1.mean(axis=1)
    assert np.max(np.abs(p1 - p0)) > 0.05  # blurred
    assert abs(p1[50] - 0.5) < 1e-4 and abs(p0[50] - 0.5) < 1e-4  # centred on mid-exposure
    # a wider edge: the 20 %..80 % rise takes more rows with smear (monotone profile from 0.2 to 0.8)
    rise = [np.count_nonzero((p > 0.32) & (p < 0.68)) for p in (p0, p1)]
    assert rise[1] > rise[0]
