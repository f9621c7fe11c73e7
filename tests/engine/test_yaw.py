"""Issue 20, yaw steering: the detector turned to follow the ground's relative motion sees the ground rotated, not
sheared. The simulation is compared with the static image of a ground truth the test rotates itself (its own
supersampled renderer), and the edges' angles with the budget's rotation."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import satchain
from satchain import load_preset, measure_edge
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.yaw import check_band, rotate_frame, rotate_into
from satchain.errors import ConfigError
from satchain.tf.pushbroom import PushbroomTerms

BASE = load_preset("ankarasat3")
PX = 0.07
EARTH = {"orbit.latitude_deg": 0.0, "orbit.inclination_deg": 97.6, "orbit.earth_rotation": True}
YAW = BASE.replace({**EARTH, "orbit.yaw_steering": True})


def _edges(n: int, rotation_deg: float = 0.0, pivot=(0.0, 0.0), ss: int = 3):
    """A near-vertical and a near-horizontal 5 deg edge (0.2 / 0.6), pixel-averaged over ss x ss points, of the
    ground rotated so that the value at q is the unrotated ground's at P + M (q - P) (the yaw's map)."""
    g = math.radians(rotation_deg)
    c, s = math.cos(g), math.sin(g)
    t5 = math.tan(math.radians(5.0))
    v, h = np.zeros((n, n)), np.zeros((n, n))
    for oy in range(ss):
        for ox in range(ss):
            y, x = np.mgrid[0:n, 0:n].astype(float)
            y += (oy + 0.5) / ss
            x += (ox + 0.5) / ss
            xr = pivot[0] + c * (x - pivot[0]) + s * (y - pivot[1])
            yr = pivot[1] - s * (x - pivot[0]) + c * (y - pivot[1])
            v += xr - (n / 2 + (yr - n / 2) * t5) > 0
            h += yr - (n / 2 + (xr - n / 2) * t5) > 0
    return 0.2 + 0.4 * v / ss**2, 0.2 + 0.4 * h / ss**2


@pytest.fixture(scope="module")
def yawed():
    v, h = _edges(1400)
    return v, h, satchain.simulate_image(v, YAW, pixel_m=PX).image, satchain.simulate_image(h, YAW, pixel_m=PX).image


def test_the_yawed_image_is_the_static_image_of_the_rotated_ground(yawed):
    """Reference: the ground rotated by the test about the output grid's centre, imaged statically with the same
    along-track scale (a line-rate error equal to the relative speed's) -- agrees within 1e-3 inside."""
    v, _, mv, _ = yawed
    t = PushbroomTerms(YAW)
    gamma = t.geometry()["rotation_deg"]
    ny, nx = mv.shape
    pivot = (nx * YAW.gsd_act_m / 2 / PX, ny * YAW.gsd_alt_m / 2 / PX)
    vr, _ = _edges(1400, gamma, pivot)
    ref = satchain.simulate_image(vr, BASE.replace({"motion.line_rate_error": t.drift_px[1]}), pixel_m=PX).image
    assert ref.shape == mv.shape
    inner = np.s_[20:-20, 20:-20]
    assert np.abs(ref - mv)[inner].max() < 1e-3
    assert abs(gamma) > 3.5  # a real rotation (lat 0, i 97.6: ~3.75 deg)


def test_both_edges_turn_by_the_same_angle_rotated_not_sheared(yawed):
    _, _, mv, mh = yawed
    t = PushbroomTerms(YAW)
    g = t.geometry()
    assert g["shear_deg"] == 0.0 and g["rotation_deg"] != 0.0
    A = t.image_affine(mv.shape)
    lin = np.array([[A.a, A.b], [A.d, A.e]])
    t5 = math.tan(math.radians(5))
    dv, dh = lin @ [t5, 1.0], lin @ [1.0, t5]
    pv, ph = math.degrees(math.atan2(dv[0], dv[1])), math.degrees(math.atan2(dh[1], dh[0]))
    k = mv.shape[0] // 2
    av = measure_edge(mv[k - 60 : k + 60, k - 30 : k + 30]).angle_deg
    ah = 90 - measure_edge(mh[k - 30 : k + 30, k - 60 : k + 60]).angle_deg
    assert abs(av - pv) < 0.05 and abs(ah - ph) < 0.05
    turned_v, turned_h = av - 5.0, 5.0 - ah  # the same turn, in the same sense, for both: a rotation
    assert abs(turned_v - turned_h) < 0.1 and abs(abs(turned_v) - abs(g["rotation_deg"])) < 0.1


def test_the_image_affine_places_the_edge_where_it_is_imaged(yawed):
    _, _, mv, _ = yawed
    A = PushbroomTerms(YAW).image_affine(mv.shape)
    col, row = A @ (700 * PX, 700 * PX)  # the edges' crossing point, ground metres
    r = int(round(row))
    res = measure_edge(mv[r - 40 : r + 41, int(col) - 30 : int(col) + 30])
    slope = math.tan(math.radians(res.angle_deg))
    at_row = res.edge_position_px[40] + int(col) - 30 + (row - r) * slope
    assert abs(at_row - col) < 0.05


@settings(max_examples=25, deadline=None)
@given(angle=st.floats(-12.0, 12.0), py=st.floats(10.0, 50.0), px=st.floats(10.0, 50.0))
def test_three_shears_rotate_a_band_limited_pattern_exactly(angle, py, px):
    """A Gaussian blob (band-limited to 1e-12 well below Nyquist) rotated about any pivot, against its formula."""
    n, sig = 64, 3.0
    y, x = np.mgrid[0:n, 0:n].astype(float)
    blob = np.exp(-((x - 30) ** 2 + (y - 33) ** 2) / (2 * sig**2))
    out = rotate_frame(blob, angle, (py, px))
    g = math.radians(angle)
    xr = px + math.cos(g) * (x - px) + math.sin(g) * (y - py)
    yr = py - math.sin(g) * (x - px) + math.cos(g) * (y - py)
    assert np.abs(out - np.exp(-((xr - 30) ** 2 + (yr - 33) ** 2) / (2 * sig**2))).max() < 1e-6


def test_what_the_rotation_cannot_do_exactly_is_refused():
    with pytest.raises(ConfigError, match="yaw_steering.*Nyquist"):
        check_band(0.45, 0.499, 10.0)
    check_band(0.4, 0.499, 3.8)  # the preset's geometry passes
    with pytest.raises(ConfigError, match="periodic.*yaw_steering"):
        Simulator(YAW, input_pixel_m=PX, input_shape=(700, 700), params=SimParams(border="periodic"))


def test_a_streamed_yawed_simulation_equals_the_in_memory_one(yawed):
    """The rotated frame goes to disk beside the coarse grid and stage 2 streams in tiles, far field included:
    within the streamed path's bound of the in-memory image (1e-5 of the range at a 64-px margin)."""
    from satchain.engine.sources import ArraySource
    from satchain.engine.stream import coarse_store, stream_tiles

    v, _, mv, _ = yawed
    src = ArraySource(v, pixel_m=PX)
    sim = Simulator(YAW, input_pixel_m=PX, input_shape=v.shape, params=SimParams(stream_tile_px=64))
    full = sim.form_image(sim.decimate(src))
    assert np.array_equal(full, mv)  # the API's in-memory image is this one
    out = np.full(sim.output_shape, np.nan)
    with coarse_store(sim) as coarse:
        sim.decimate(src, out=coarse)
        for r0, c0, t in stream_tiles(sim, coarse):
            out[r0 : r0 + t.shape[0], c0 : c0 + t.shape[1]] = t
        assert isinstance(sim._yaw_cache[1], np.memmap)  # the rotated frame lives on disk
    assert sim._yaw_cache is None and sim.yaw_store is None
    assert np.max(np.abs(out - full)) / np.ptp(full) < 1e-5


def test_the_rotation_out_of_core_equals_the_rotation_in_memory():
    rng = np.random.default_rng(4)
    frame = rng.normal(size=(96, 80)).astype(np.float32)
    whole = rotate_frame(frame, 5.0, (40.0, 37.0))
    out = np.empty_like(frame)
    rotate_into(lambda a, h: frame[a : a + h], frame.shape, out, 5.0, (40.0, 37.0), band_bytes=16 * 80 * 7)
    assert np.array_equal(out, whole)  # bands of 7 rows / a few columns: the same transforms
