"""The Python API's inputs (issue 29 item 8): numpy masked arrays, integer and boolean dtypes, and a partial
``quality`` mapping for :func:`satchain.predict`.

A masked pixel is no data everywhere, as NaN and a ``valid = False`` pixel already are: ``simulate_image``
takes it as no data (its output is masked where a masked pixel reaches), ``simulate`` refuses it (as it refuses
NaN), the measurements that take ``valid`` leave it out, the others refuse it in their region. Images are
rendered here (tests/measure/_render_edge.py, _render_chart.py: exact, independent of satchain).
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import numpy as np
import pytest

import satchain
from satchain.errors import ConfigError, InputError

sys.path.insert(0, str(Path(__file__).resolve().parent / "measure"))  # the exact renderers

from _render_chart import render_chart  # noqa: E402
from _render_edge import render_iso_edge, truth_mtf  # noqa: E402
from _render_wedge import linear, render_wedge, widths_at_columns  # noqa: E402

SYSTEM = satchain.load_preset("ankarasat3")  # GSD 0.49 m
Q = 1.07  # the rendered edges' optics (annular, cutoff 1 / Q cy/px)


@functools.lru_cache(maxsize=8)
def _unit_edge(shape=(96, 96), angle_deg=5.0, offset_px=0.137) -> np.ndarray:
    out = render_iso_edge(shape, angle_deg, q=Q, offset_px=offset_px)
    out.flags.writeable = False
    return out


def _edge(shape=(96, 96), angle_deg=5.0, offset_px=0.137):
    return 0.2 + 0.6 * _unit_edge(shape, angle_deg, offset_px)


def _masked(a, mask):
    return np.ma.masked_array(a, mask=mask)


# ------------------------------------------------------------------------------------------ simulate_image
def test_simulate_image_takes_masked_pixels_as_no_data_and_returns_a_masked_image():
    """A uniform 0.3 scene whose masked corner holds 1e6: the output is 0.3 wherever no masked pixel reaches,
    and masked exactly over the output pixels whose 5 x 5 input cell holds a masked pixel."""
    a = np.full((140, 140), 0.3)
    mask = np.zeros(a.shape, bool)
    mask[:33, :48] = True
    a[mask] = 1e6  # what lies under the mask is no data
    r = satchain.simulate_image(_masked(a, mask), SYSTEM, pixel_m=0.098)  # k = 0.49 / 0.098 = 5
    expected = mask.reshape(28, 5, 28, 5).any(axis=(1, 3))  # cells touching a masked pixel
    assert isinstance(r.image, np.ma.MaskedArray)
    np.testing.assert_array_equal(np.ma.getmaskarray(r.image), expected)
    np.testing.assert_array_equal(r.valid, ~expected)
    np.testing.assert_allclose(r.image.compressed(), 0.3, atol=1e-9)


def test_simulate_image_refuses_a_fully_masked_array():
    a = np.full((60, 60), 0.3)
    with pytest.raises(InputError, match="NaN or masked"):
        satchain.simulate_image(_masked(a, np.ones(a.shape, bool)), SYSTEM, pixel_m=0.098)


def test_simulate_image_masked_array_without_masked_pixels_is_the_plain_array():
    a = np.full((70, 70), 0.3)
    r = satchain.simulate_image(np.ma.masked_array(a), SYSTEM, pixel_m=0.098)
    assert r.valid is None
    np.testing.assert_allclose(np.asarray(r.image), 0.3, atol=1e-9)


@pytest.mark.parametrize(("dtype", "stored"), [(np.uint8, 77), (np.uint16, 77 * 257), (np.int16, 77 * 128)])
def test_simulate_image_scales_8_and_16_bit_dn_by_their_range(dtype, stored):
    """uint8 77 = uint16 77 * 257 = reflectance 77 / 255; int16 by 2**15 - 1 (documented)."""
    full = {np.uint8: 255.0, np.uint16: 65535.0, np.int16: 32767.0}[dtype]
    r = satchain.simulate_image(np.full((70, 70), stored, dtype=dtype), SYSTEM, pixel_m=0.098)
    np.testing.assert_allclose(r.image, stored / full, rtol=1e-6)


@pytest.mark.parametrize("dtype", [np.int32, np.int64, np.uint32, np.uint64])
def test_simulate_image_wide_integers_need_input_scale(dtype):
    """np.array of Python ints is int64: its width is no DN range (was: 200 -> 2e-17 reflectance)."""
    a = np.full((70, 70), 200, dtype=dtype)
    with pytest.raises(InputError, match=rf"dtype {np.dtype(dtype)} states no DN range.*input_scale"):
        satchain.simulate_image(a, SYSTEM, pixel_m=0.098)
    r = satchain.simulate_image(a, SYSTEM, pixel_m=0.098, input_scale=1 / 1000)
    np.testing.assert_allclose(r.image, 0.2, rtol=1e-6)


def test_simulate_image_and_simulate_refuse_a_boolean_array():
    a = np.ones((70, 70), bool)
    with pytest.raises(InputError, match="boolean array is a mask"):
        satchain.simulate_image(a, SYSTEM, pixel_m=0.098)
    with pytest.raises(InputError, match="boolean array is a mask"):
        satchain.simulate(a, SYSTEM, pixel_m=0.098)


def test_simulate_refuses_masked_pixels_and_takes_an_unmasked_masked_array():
    a = np.full((70, 70), 0.3)
    mask = np.zeros(a.shape, bool)
    mask[3, 4] = True
    with pytest.raises(InputError, match=r"1 pixel\(s\) are masked.*simulate_image"):
        satchain.simulate(_masked(a, mask), SYSTEM, pixel_m=0.098)
    np.testing.assert_allclose(satchain.simulate(np.ma.masked_array(a), SYSTEM, pixel_m=0.098), 0.3, atol=1e-9)


# ------------------------------------------------------------------------------------------ measure_edge
def test_measure_edge_leaves_masked_pixels_out():
    """Rows 0-29 hold an edge 3 px away under a mask: the MTF is the rendered optics' (0.3142 at Nyquist)."""
    img = _edge()
    img[:30] = _edge(offset_px=3.137)[:30]
    mask = np.zeros(img.shape, bool)
    mask[:30] = True
    r = satchain.measure_edge(_masked(img, mask))
    assert r.mtf_at_nyquist == pytest.approx(float(truth_mtf(0.5, q=Q)), abs=0.003)
    assert r.n_lines <= 96 - 30  # the lines used are the unmasked ones


def test_measure_edge_refuses_a_fully_masked_image_or_region():
    img = _edge()
    with pytest.raises(InputError, match="every pixel is masked"):
        satchain.measure_edge(_masked(img, np.ones(img.shape, bool)))
    mask = np.zeros(img.shape, bool)
    mask[:, :48] = True
    with pytest.raises(InputError, match="valid pixel"):
        satchain.measure_edge(_masked(img, mask), roi=(0, 0, 40, 96))


def test_measure_edge_combines_the_mask_with_valid():
    img = _edge()
    mask = np.zeros(img.shape, bool)
    mask[:40] = True
    valid = np.ones(img.shape, bool)
    valid[40:] = False
    with pytest.raises(InputError, match="every pixel is"):
        satchain.measure_edge(_masked(img, mask), valid=valid)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int32, np.int64])
def test_measure_edge_takes_integer_values_as_they_stand(dtype):
    """The edge in DN 20-220 of any integer dtype: its contrast is 200 DN, and its MTF that of the same values
    as floats (no scaling by the dtype's range, no clipping at a dtype's maximum it does not reach)."""
    values = np.round(20 + 200 * _unit_edge())
    r = satchain.measure_edge(values.astype(dtype))
    assert abs(r.contrast) == pytest.approx(200, abs=2)
    np.testing.assert_array_equal(r.mtf, satchain.measure_edge(values).mtf)
    assert r.flags == ()


def test_measures_refuse_a_boolean_image():
    with pytest.raises(InputError, match="boolean array is a mask"):
        satchain.measure_edge(_edge() > 0.5)
    with pytest.raises(InputError, match="boolean array is a mask"):
        satchain.find_edges(np.ones((64, 64), bool))


# ------------------------------------------------------------------------------------------ find_edges
_SQUARES = [(60.3, 100.0, 70, 5.0), (180.0, 100.6, 70, 8.0)]


def test_find_edges_finds_no_edge_in_the_mask():
    """Two squares; the right one under a mask: only the left square's four sides, each centre outside it."""
    img = render_chart((200, 240), _SQUARES, sx=0.45, sy=0.6)
    mask = np.zeros(img.shape, bool)
    mask[:, 125:] = True
    s = satchain.find_edges(_masked(img, mask))
    assert len(s) == 4
    for c in s.candidates:
        assert c.center_xy[0] < 125 - 3
    found = satchain.measure_found_edges(_masked(img, mask))
    assert len(found.edges) == 4


def test_find_edges_refuses_a_fully_masked_image():
    img = render_chart((200, 240), _SQUARES, sx=0.45, sy=0.6)
    with pytest.raises(InputError, match="every pixel is masked"):
        satchain.find_edges(_masked(img, np.ones(img.shape, bool)))
    with pytest.raises(InputError, match="every pixel is masked"):
        satchain.measure_found_edges(_masked(img, np.ones(img.shape, bool)))


# ------------------------------------------------------------------------------------------ the other measurements
def _star(n=24, size=97, c=48.3):
    y, x = np.mgrid[0:size, 0:size].astype(float)
    return 100 + 40 * np.cos(n * np.arctan2(y - c, x - c))


def test_measure_star_refuses_masked_pixels_in_its_region():
    img = _star()
    mask = np.zeros(img.shape, bool)
    mask[10, 50] = True
    with pytest.raises(InputError, match="masked"):
        satchain.measure_star(_masked(img, mask), cycles=24)


def test_measure_bars_refuses_a_group_with_masked_pixels():
    x = np.arange(64.0)
    img = np.tile(125 + 37.5 * np.cos(2 * np.pi * (x - 1.3) / 8), (20, 1))
    mask = np.zeros(img.shape, bool)
    mask[5, 30] = True
    with pytest.raises(InputError, match="masked"):
        satchain.measure_bars(_masked(img, mask), periods_px=[8.0], group_rois=[(0, 0, 64, 20)], levels=(50.0, 200.0))


def test_measure_wedge_refuses_masked_pixels_in_its_region():
    width = linear(3.0, 0.01)
    img = render_wedge(width, rows=48, cols=160, blur=0.8)
    mask = np.zeros(img.shape, bool)
    mask[20, 80] = True
    with pytest.raises(InputError, match="masked"):
        satchain.measure_wedge(_masked(img, mask), line_width_px=widths_at_columns(width, 160))


def test_measure_jitter_refuses_a_fully_masked_image():
    from satchain.measure import measure_jitter

    img = _edge((128, 64))
    with pytest.raises(InputError, match="every pixel is masked"):
        measure_jitter(_masked(img, np.ones(img.shape, bool)), line_time_s=1e-3)


def _scene_and_truth():
    from satchain.scene import Scene, SlantedEdge

    scene = Scene(30.0, 30.0, (SlantedEdge("e", center_m=(15.0, 15.0), size_m=24.0),), pixel_m=0.25)
    return scene.render().reshape(60, 2, 60, 2).mean(axis=(1, 3)), scene.truth()


def test_measure_snr_refuses_masked_pixels():
    img, truth = _scene_and_truth()
    mask = np.zeros(img.shape, bool)
    mask[0, 0] = True
    with pytest.raises(InputError, match=r"1 pixel\(s\) are masked"):
        satchain.measure_snr(_masked(img, mask), truth, pixel_m=0.5)


def test_measure_auto_leaves_masked_pixels_out_of_its_calibration_and_edges():
    """The image is reflectance (gain 1, offset 0); a masked band of rows holds 10x the values: the
    calibration and the edge's angle (the truth's 5 deg) are those of the unmasked pixels."""
    img, truth = _scene_and_truth()
    mask = np.zeros(img.shape, bool)
    mask[10:20] = True
    img[mask] *= 10.0
    r = satchain.measure_auto(_masked(img, mask), truth, pixel_m=0.5)
    assert r.calibration["fitted"]
    assert r.calibration["gain"] == pytest.approx(1.0, abs=0.03)
    assert r.calibration["offset"] == pytest.approx(0.0, abs=0.01)
    (edge,) = r.to_dict()["slanted_edges"]
    assert edge["angle_deg"] == pytest.approx(5.0, abs=0.1)


# ------------------------------------------------------------------------------------------ predict(quality=...)
_TRUTH = {"items": []}


def test_predict_fills_a_partial_quality_from_the_system():
    """{"snr": 50}: the system's RER, and the GIQE 5 NIIRS of that RER at SNR 50 (NGA's formula, written out)."""
    q = satchain.predict_quality(SYSTEM)
    p = satchain.predict(SYSTEM, _TRUTH, quality={"snr": 50.0})
    assert p.snr == 50.0
    assert p.rer == pytest.approx(q.rer_giqe5, rel=1e-12)
    g = q.gsd_in / np.sin(np.deg2rad(SYSTEM.orbit.elevation_deg)) ** 0.25
    lr = np.log10(q.rer_giqe5)
    niirs = 9.57 - 3.32 * np.log10(g) + 3.32 * (1 - np.exp(-1.9 / 50)) * lr - 2 * lr**4 - 1.8 / 50
    assert p.giqe5 == pytest.approx(niirs, abs=1e-9)
    full = satchain.predict(SYSTEM, _TRUTH, quality=q.to_dict())  # a whole to_dict() as before
    assert (full.giqe5, full.rer, full.snr) == (q.giqe5, q.rer_giqe5, q.snr)
    given = satchain.predict(SYSTEM, _TRUTH, quality={"giqe5": 4.0})
    assert (given.giqe5, given.rer, given.snr) == (4.0, q.rer_giqe5, q.snr)


def test_predict_refuses_an_unknown_quality_key_naming_it_and_the_allowed_ones():
    with pytest.raises(ConfigError, match=r"quality: unknown key\(s\) 'snr_'; allowed: .*rer_giqe5.*snr"):
        satchain.predict(SYSTEM, _TRUTH, quality={"snr_": 50.0})


@pytest.mark.parametrize(("key", "value"), [("snr", float("nan")), ("rer_giqe5", 0.0), ("giqe5", "5")])
def test_predict_refuses_a_quality_figure_that_is_no_number(key, value):
    with pytest.raises(ConfigError, match=rf"quality\['{key}'\] = "):
        satchain.predict(SYSTEM, _TRUTH, quality={key: value})


@pytest.mark.parametrize(("key", "value"), [("rer", 0.3), ("gsd_m", 1.0), ("otf_kind", "x"), ("giqe4", 9.0)])
def test_predict_refuses_a_quality_figure_it_does_not_use_unless_it_is_the_systems_own(key, value):
    """{"rer": 0.3} used to be accepted and ignored (the NIIRS came from the system's rer_giqe5): refused, naming
    the key and the keys predict uses; a whole record of this system (the pipeline's) is still taken."""
    with pytest.raises(ConfigError, match=rf"quality\['{key}'\] = .*not use.*giqe5, rer_giqe5, snr"):
        satchain.predict(SYSTEM, _TRUTH, quality={key: value})
    q = satchain.predict_quality(SYSTEM).to_dict()
    with pytest.raises(ConfigError, match=rf"quality\['{key}'\]"):  # an edited whole record
        satchain.predict(SYSTEM, _TRUTH, quality={**q, key: value})
    own = satchain.predict(SYSTEM, _TRUTH, quality={key: q[key], "snr": 50.0})  # the system's own value: harmless
    assert own.snr == 50.0 and own.rer == q["rer_giqe5"]
